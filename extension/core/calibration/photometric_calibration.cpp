#include "photometric_calibration.h"
#include <io/yaml_fields.h>

#include <io/image_codec.h>

#include <camera/omni_camera.h>

#include <opencv2/photo.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace roomprobe {

namespace fs = std::filesystem;

namespace {

// Codes this low carry mostly quantisation; the fits leave them out, as they leave out clipped ones.
constexpr int DARK_CODE = 8;

bool usable_code(const cv::Vec3b &p_code, int p_saturation) {
	for (int c = 0; c < 3; c++) {
		if (p_code[c] <= DARK_CODE || p_code[c] >= p_saturation) {
			return false;
		}
	}
	return true;
}

cv::Mat read_rgb(const fs::path &p_path, cv::Size p_size, std::string *r_error) {
	cv::Mat bgr;
	const std::string error = image_read(p_path.string(), ImageReadMode::Bgr8, &bgr);
	if (!error.empty()) {
		*r_error = error;
		return cv::Mat();
	}
	if (p_size.area() > 0 && bgr.size() != p_size) {
		*r_error = p_path.string() + ": " + std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows) + ", the fisheye's images are " +
				std::to_string(p_size.width) + "x" + std::to_string(p_size.height);
		return cv::Mat();
	}
	cv::Mat rgb;
	cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
	return rgb;
}

} // namespace

PhotometricViews load_photometric_views(const std::string &p_folder, cv::Size p_fisheye_size) {
	PhotometricViews views;
	const fs::path root(p_folder);
	const fs::path path = root / "photometric.yaml";
	std::error_code ec;
	if (!fs::exists(path, ec)) {
		return views;
	}
	views.present = true;
	const std::string name = path.string();
	try {
		cv::FileStorage file;
		const std::string problem = open_yaml_file(name, &file);
		if (!problem.empty()) {
			views.error = problem;
			return views;
		}
		const auto positive = [&](const cv::FileNode &p_node, const std::string &p_field, double *r_value) {
			if (p_node.empty() || (!p_node.isReal() && !p_node.isInt())) {
				views.error = name + ": " + p_field + ": missing, or not a number";
				return false;
			}
			*r_value = double(p_node);
			if (!(*r_value > 0.0) || !std::isfinite(*r_value)) {
				views.error = name + ": " + p_field + ": must be a positive number of microseconds";
				return false;
			}
			return true;
		};
		if (!positive(file["reference_exposure_us"], "reference_exposure_us", &views.reference_exposure_us)) {
			return views;
		}
		const cv::FileNode sweep = file["exposure_sweep"];
		if (!sweep.isSeq()) {
			views.error = name + ": exposure_sweep: must be a list of {image, exposure_us}";
			return views;
		}
		for (size_t i = 0; i < sweep.size(); i++) {
			const std::string field = "exposure_sweep[" + std::to_string(i) + "]";
			const cv::FileNode item = sweep[int(i)];
			double exposure_us = 0.0;
			if (!item.isMap() || item["image"].empty() || !item["image"].isString()) {
				views.error = name + ": " + field + ".image: missing";
				return views;
			}
			if (!positive(item["exposure_us"], field + ".exposure_us", &exposure_us)) {
				return views;
			}
			const cv::Mat image = read_rgb(root / std::string(item["image"]), p_fisheye_size, &views.error);
			if (image.empty()) {
				return views;
			}
			views.sweep.push_back(image);
			views.sweep_exposure_us.push_back(exposure_us);
		}
		const cv::FileNode flat = file["flat_field"];
		if (!flat.empty()) {
			if (!flat.isMap() || flat["image"].empty() || !flat["image"].isString()) {
				views.error = name + ": flat_field.image: missing";
				return views;
			}
			views.flat_field = read_rgb(root / std::string(flat["image"]), p_fisheye_size, &views.error);
			if (views.flat_field.empty()) {
				return views;
			}
		}
	} catch (const cv::Exception &e) {
		views.error = name + ": cannot read it (" + e.err + ")";
	}
	return views;
}

ResponseFit fit_response(const std::vector<cv::Mat> &p_sweep, const std::vector<double> &p_exposure_us, const OmniParams &p_fisheye) {
	ResponseFit fit;
	if (p_sweep.size() < 3 || p_sweep.size() != p_exposure_us.size()) {
		fit.error = "the exposure sweep needs at least 3 images with their exposures (got " + std::to_string(p_sweep.size()) + ")";
		return fit;
	}
	const auto [shortest, longest] = std::minmax_element(p_exposure_us.begin(), p_exposure_us.end());
	if (!(*longest >= 16.0 * *shortest)) {
		fit.error = "the exposure sweep spans less than 4 stops (its longest exposure is " + std::to_string(*longest / *shortest) +
				" times its shortest): the response's ends cannot be seen";
		return fit;
	}
	// The square inside the image circle: every pixel there sees the scene.
	const auto [cx, cy, radius] = lens_circle(p_fisheye);
	const int half = int(radius * 0.69);
	const cv::Rect crop = cv::Rect(int(cx) - half, int(cy) - half, 2 * half, 2 * half) & cv::Rect(0, 0, p_sweep[0].cols, p_sweep[0].rows);
	if (crop.width < 16 || crop.height < 16) {
		fit.error = "the fisheye's image circle is too small for the response fit";
		return fit;
	}
	std::vector<cv::Mat> images;
	std::vector<float> times;
	for (size_t i = 0; i < p_sweep.size(); i++) {
		if (p_sweep[i].type() != CV_8UC3 || p_sweep[i].size() != p_sweep[0].size()) {
			fit.error = "the exposure sweep's images must be 8-bit colour images of one size";
			return fit;
		}
		images.push_back(p_sweep[i](crop).clone());
		times.push_back(float(p_exposure_us[i] * 1e-6));
	}
	cv::Mat response;
	cv::createCalibrateDebevec(400, 10.0f, false)->process(images, response, times);
	if (response.rows != 256 || response.type() != CV_32FC3) {
		fit.error = "cv::CalibrateDebevec gave no response";
		return fit;
	}
	for (int c = 0; c < 3; c++) {
		const double mid = response.at<cv::Vec3f>(128)[c];
		if (!(mid > 0.0) || !std::isfinite(mid)) {
			fit.error = "cv::CalibrateDebevec's response is not finite";
			return fit;
		}
		float running = 0.0f;
		for (int k = 0; k < 256; k++) {
			// Debevec's curve may dip at the ends, where few samples fall; a response only rises.
			running = std::max(running, float(response.at<cv::Vec3f>(k)[c] / mid));
			fit.response[size_t(c)][size_t(k)] = running;
		}
	}
	// The residual on a grid of the crop: each pixel's log radiance from the usable exposures.
	double sum2 = 0.0;
	size_t n = 0;
	const int grid = 24;
	for (int gy = 0; gy < grid; gy++) {
		for (int gx = 0; gx < grid; gx++) {
			const cv::Point p(crop.x + (gx * 2 + 1) * crop.width / (2 * grid), crop.y + (gy * 2 + 1) * crop.height / (2 * grid));
			for (int c = 0; c < 3; c++) {
				std::vector<double> logs;
				for (size_t i = 0; i < p_sweep.size(); i++) {
					const int code = p_sweep[i].at<cv::Vec3b>(p)[c];
					if (code > DARK_CODE && code < 245) {
						logs.push_back(std::log(fit.response[size_t(c)][size_t(code)]) - std::log(p_exposure_us[i]));
					}
				}
				if (logs.size() < 2) {
					continue;
				}
				double mean = 0.0;
				for (double l : logs) {
					mean += l / double(logs.size());
				}
				for (double l : logs) {
					sum2 += (l - mean) * (l - mean);
					n++;
				}
			}
		}
	}
	fit.samples = n;
	fit.rms_ln = n ? std::sqrt(sum2 / double(n)) : 0.0;
	return fit;
}

VignettingFit fit_vignetting(const cv::Mat &p_flat_field, const std::array<ResponseCurve, 3> &p_response, const OmniParams &p_fisheye, int p_nodes) {
	VignettingFit fit;
	if (p_flat_field.type() != CV_8UC3 || p_nodes < 2) {
		fit.error = "the flat field must be an 8-bit colour image";
		return fit;
	}
	const auto [cx, cy, radius] = lens_circle(p_fisheye);
	// Least squares of the table's piecewise-linear curve (hat functions at the nodes) through the
	// linearised values: normal equations, tridiagonal.
	cv::Mat normal(p_nodes, p_nodes, CV_64F, cv::Scalar(0.0)), rhs(p_nodes, 1, CV_64F, cv::Scalar(0.0));
	std::vector<double> weight(size_t(p_nodes), 0.0);
	struct Sample {
		double r, value;
	};
	std::vector<Sample> samples;
	for (int y = 0; y < p_flat_field.rows; y++) {
		const cv::Vec3b *row = p_flat_field.ptr<cv::Vec3b>(y);
		for (int x = 0; x < p_flat_field.cols; x++) {
			const double r = std::hypot(x - cx, y - cy) / radius;
			if (r > 1.0 || !usable_code(row[x], 250)) {
				continue;
			}
			const double value = p_response[0][row[x][0]] + p_response[1][row[x][1]] + p_response[2][row[x][2]];
			const double position = r * (p_nodes - 1);
			const int i = std::min(int(position), p_nodes - 2);
			const double t = position - double(i);
			const double a = 1.0 - t, b = t;
			normal.at<double>(i, i) += a * a;
			normal.at<double>(i, i + 1) += a * b;
			normal.at<double>(i + 1, i) += a * b;
			normal.at<double>(i + 1, i + 1) += b * b;
			rhs.at<double>(i) += a * value;
			rhs.at<double>(i + 1) += b * value;
			weight[size_t(i)] += a;
			weight[size_t(i) + 1] += b;
			samples.push_back({ r, value });
		}
	}
	for (int i = 0; i < p_nodes; i++) {
		if (!(weight[size_t(i)] > 0.5)) {
			fit.error = "the flat field has no usable pixel (neither dark nor clipped) near " + std::to_string(int(100.0 * i / (p_nodes - 1))) +
					" % of the image circle's radius";
			return fit;
		}
	}
	cv::Mat nodes;
	if (!cv::solve(normal, rhs, nodes, cv::DECOMP_CHOLESKY) || !(nodes.at<double>(0) > 0.0)) {
		fit.error = "the flat field's fall-off could not be fitted";
		return fit;
	}
	const double centre = nodes.at<double>(0);
	for (int i = 0; i < p_nodes; i++) {
		fit.table.push_back(float(nodes.at<double>(i) / centre));
	}
	fit.table[0] = 1.0f;
	double sum2 = 0.0;
	for (const Sample &s : samples) {
		const double predicted = centre * vignetting_at(fit.table, s.r);
		sum2 += (s.value / predicted - 1.0) * (s.value / predicted - 1.0);
	}
	fit.rms = samples.empty() ? 0.0 : std::sqrt(sum2 / double(samples.size()));
	return fit;
}

ColourFit fit_colour_gains(const BoardSpec &p_board, const std::vector<BoardPair> &p_pairs, const CameraPhotometry &p_fisheye_linear,
		const OmniParams &p_fisheye, const CameraPhotometry &p_rgb) {
	ColourFit fit;
	// Per square seen by both cameras: the mean linear colour in each camera over a small window
	// at its centre (the mean of its four corners), where no pixel is dark or clipped.
	struct Square {
		glm::dvec3 fisheye{ 0.0 }, rgb{ 0.0 };
	};
	std::vector<Square> squares;
	const auto window_mean = [](const cv::Mat &p_image, const cv::Point2f &p_centre, double p_half, const CameraPhotometry &p_camera, const OmniParams *p_lens,
									 glm::dvec3 *r_mean) {
		const int h = int(p_half);
		if (h < 1) {
			return false;
		}
		glm::dvec3 sum(0.0);
		int n = 0;
		for (int dy = -h; dy <= h; dy++) {
			for (int dx = -h; dx <= h; dx++) {
				const int x = int(std::lround(p_centre.x)) + dx, y = int(std::lround(p_centre.y)) + dy;
				if (x < 0 || y < 0 || x >= p_image.cols || y >= p_image.rows) {
					return false;
				}
				const cv::Vec3b code = p_image.at<cv::Vec3b>(y, x);
				if (!usable_code(code, p_camera.saturation_code)) {
					return false;
				}
				const double vignetting = p_lens ? vignetting_at(p_camera.vignetting, circle_radius_fraction(*p_lens, glm::dvec2(x, y))) : 1.0;
				for (int c = 0; c < 3; c++) {
					sum[c] += p_camera.response[size_t(c)][code[c]] * p_camera.channel_gains[c] / vignetting;
				}
				n++;
			}
		}
		*r_mean = sum / double(n);
		return true;
	};
	for (const BoardPair &pair : p_pairs) {
		if (pair.rgb_image.type() != CV_8UC3 || pair.fisheye_image.type() != CV_8UC3) {
			continue;
		}
		for (int j = 0; j + 1 < p_board.inner_y; j++) {
			for (int i = 0; i + 1 < p_board.inner_x; i++) {
				const size_t a = size_t(j) * p_board.inner_x + i, b = a + 1, c = a + p_board.inner_x, d = c + 1;
				Square square;
				bool ok = true;
				for (int camera = 0; camera < 2 && ok; camera++) {
					const std::vector<cv::Point2f> &k = camera == 0 ? pair.rgb.corners : pair.fisheye.corners;
					const cv::Point2f centre = (k[a] + k[b] + k[c] + k[d]) * 0.25f;
					const double side = std::min(cv::norm(k[b] - k[a]), cv::norm(k[c] - k[a]));
					ok = camera == 0 ? window_mean(pair.rgb_image, centre, 0.25 * side, p_rgb, nullptr, &square.rgb)
									 : window_mean(pair.fisheye_image, centre, 0.25 * side, p_fisheye_linear, &p_fisheye, &square.fisheye);
				}
				if (ok) {
					squares.push_back(square);
				}
			}
		}
	}
	if (squares.size() < 4) {
		fit.error = "the colour transform needs board squares both cameras see neither dark nor clipped in the pairs (found " +
				std::to_string(squares.size()) + ")";
		return fit;
	}
	for (int c = 0; c < 3; c++) {
		double fr = 0.0, ff = 0.0;
		for (const Square &s : squares) {
			fr += s.fisheye[c] * s.rgb[c];
			ff += s.fisheye[c] * s.fisheye[c];
		}
		fit.gains[c] = fr / ff;
	}
	double sum2 = 0.0;
	for (const Square &s : squares) {
		for (int c = 0; c < 3; c++) {
			const double e = fit.gains[c] * s.fisheye[c] / s.rgb[c] - 1.0;
			sum2 += e * e;
		}
	}
	fit.squares = squares.size();
	fit.rms = std::sqrt(sum2 / (3.0 * double(squares.size())));
	return fit;
}

PhotometricCalibration calibrate_photometry(const PhotometricViews &p_views, const BoardSpec &p_board, const std::vector<BoardPair> &p_pairs,
		const OmniParams &p_fisheye) {
	PhotometricCalibration result;
	if (!p_views.error.empty()) {
		result.error = p_views.error;
		return result;
	}
	if (!p_views.present) {
		result.error = "no photometric.yaml beside the views: the rig's photometry is not calibrated (calib/README.md says how to take the views)";
		return result;
	}
	const ResponseFit response = fit_response(p_views.sweep, p_views.sweep_exposure_us, p_fisheye);
	if (!response.error.empty()) {
		result.error = "response: " + response.error;
		return result;
	}
	CameraPhotometry fisheye;
	fisheye.response = response.response;
	if (!p_views.flat_field.empty()) {
		const VignettingFit vignetting = fit_vignetting(p_views.flat_field, response.response, p_fisheye);
		if (!vignetting.error.empty()) {
			result.error = "vignetting: " + vignetting.error;
			return result;
		}
		fisheye.vignetting = vignetting.table;
		result.vignetting_rms = vignetting.rms;
	}
	const CameraPhotometry rgb = tone_curve_photometry(ToneCurve::Srgb, 1.0);
	const ColourFit colour = fit_colour_gains(p_board, p_pairs, fisheye, p_fisheye, rgb);
	if (!colour.error.empty()) {
		result.error = "colour: " + colour.error;
		return result;
	}
	fisheye.channel_gains = colour.gains;
	fisheye.reference_exposure_us = p_views.reference_exposure_us;
	fisheye.reference_gain_db = 0.0;
	result.photometry.known = true;
	result.photometry.fisheye = fisheye;
	result.photometry.rgb = rgb;
	result.response_rms_ln = response.rms_ln;
	result.colour_rms = colour.rms;
	char method[256];
	std::snprintf(method, sizeof(method), "Debevec-Malik over %zu exposures, %s, gains from %zu board squares in %zu pairs; RGB camera taken as sRGB",
			p_views.sweep.size(), p_views.flat_field.empty() ? "no flat field (no vignetting)" : "vignetting from the flat field", colour.squares, p_pairs.size());
	result.method = method;
	return result;
}

} // namespace roomprobe
