#include "photometry.h"

#include <cmath>
#include <filesystem>

namespace roomprobe {

namespace {

float srgb_to_linear(float p_v) {
	return p_v <= 0.04045f ? p_v / 12.92f : std::pow((p_v + 0.055f) / 1.055f, 2.4f);
}

} // namespace

double radial_vignetting(const OmniParams &p_camera, const glm::dvec2 &p_pixel, double p_edge_gain) {
	if (!(p_edge_gain > 0.0) || p_edge_gain >= 1.0) {
		return 1.0;
	}
	double radius = p_camera.circle_radius;
	double cx = p_camera.circle_cx, cy = p_camera.circle_cy;
	if (radius <= 0.0) {
		cx = p_camera.cx;
		cy = p_camera.cy;
		radius = 0.5 * std::hypot(p_camera.width, p_camera.height);
	}
	const double r = std::hypot(p_pixel.x - cx, p_pixel.y - cy) / radius;
	const double k = std::sqrt(1.0 / p_edge_gain) - 1.0;
	const double f = 1.0 + k * r * r;
	return 1.0 / (f * f);
}

std::array<float, 256> linearising_lut(double p_exposure) {
	std::array<float, 256> lut{};
	for (int i = 0; i < 256; i++) {
		lut[size_t(i)] = float(srgb_to_linear(float(i) / 255.0f) / p_exposure);
	}
	return lut;
}

bool read_recording_photometry(const std::string &p_recording_folder, RigPhotometry *r_photometry, std::string *r_error) {
	*r_photometry = RigPhotometry();
	const std::filesystem::path path = std::filesystem::path(p_recording_folder) / "synth.yaml";
	std::error_code ec;
	if (!std::filesystem::exists(path, ec)) {
		return true;
	}
	try {
		cv::FileStorage info(path.string(), cv::FileStorage::READ);
		if (!info.isOpened()) {
			*r_error = path.string() + ": cannot be read";
			return false;
		}
		RigPhotometry p;
		p.known = true;
		const std::pair<const char *, double *> fields[] = { { "fisheye_exposure", &p.fisheye_exposure }, { "rgb_exposure", &p.rgb_exposure },
			{ "fisheye_vignetting_edge_gain", &p.fisheye_vignetting_edge_gain } };
		for (const auto &[name, value] : fields) {
			if (info[name].empty()) {
				continue;
			}
			*value = double(info[name]);
			if (!std::isfinite(*value) || *value <= 0.0) {
				*r_error = path.string() + ": " + name + ": must be a positive number";
				return false;
			}
		}
		*r_photometry = p;
		return true;
	} catch (const cv::Exception &e) {
		*r_error = path.string() + ": " + e.what();
		return false;
	}
}

void FisheyeLinearizer::configure(const RigPhotometry &p_photometry, const OmniParams &p_fisheye) {
	photometry = p_photometry;
	inverse_vignetting.release();
	if (!photometry.known) {
		return;
	}
	fisheye_lut = linearising_lut(photometry.fisheye_exposure);
	inverse_vignetting.create(p_fisheye.height, p_fisheye.width, CV_32FC1);
	for (int y = 0; y < p_fisheye.height; y++) {
		float *row = inverse_vignetting.ptr<float>(y);
		for (int x = 0; x < p_fisheye.width; x++) {
			const double v = radial_vignetting(p_fisheye, glm::dvec2(x, y), photometry.fisheye_vignetting_edge_gain);
			row[x] = v > 1e-6 ? float(1.0 / v) : 0.0f;
		}
	}
}

cv::Mat FisheyeLinearizer::linearise(const cv::Mat &p_image) const {
	if (!photometry.known || p_image.depth() != CV_8U || p_image.size() != inverse_vignetting.size()) {
		return p_image;
	}
	cv::Mat rgb = p_image;
	if (p_image.channels() == 1) {
		cv::cvtColor(p_image, rgb, cv::COLOR_GRAY2RGB);
	}
	cv::Mat out(rgb.size(), CV_32FC3);
	cv::parallel_for_(cv::Range(0, rgb.rows), [&](const cv::Range &p_rows) {
		for (int y = p_rows.start; y < p_rows.end; y++) {
			const cv::Vec3b *in = rgb.ptr<cv::Vec3b>(y);
			const float *iv = inverse_vignetting.ptr<float>(y);
			cv::Vec3f *o = out.ptr<cv::Vec3f>(y);
			for (int x = 0; x < rgb.cols; x++) {
				for (int c = 0; c < 3; c++) {
					o[x][c] = fisheye_lut[size_t(in[x][c])] * iv[x];
				}
			}
		}
	});
	return out;
}

} // namespace roomprobe
