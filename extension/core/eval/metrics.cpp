#include "metrics.h"

#include <envmap/export.h>
#include <envmap/spherical_harmonics.h>

#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace roomprobe {

cv::Mat tone_map_face(const cv::Mat &p_linear_face) {
	cv::Mat out(p_linear_face.size(), CV_8UC3);
	for (int y = 0; y < p_linear_face.rows; y++) {
		const cv::Vec3f *in = p_linear_face.ptr<cv::Vec3f>(y);
		cv::Vec3b *o = out.ptr<cv::Vec3b>(y);
		for (int x = 0; x < p_linear_face.cols; x++) {
			for (int c = 0; c < 3; c++) {
				o[x][c] = tone_map_srgb8(in[x][c]);
			}
		}
	}
	return out;
}

static double psnr_from_mse(double p_mse, double p_peak) {
	if (!(p_mse > 0.0)) {
		return PSNR_CAP_DB;
	}
	return std::min(PSNR_CAP_DB, 10.0 * std::log10(p_peak * p_peak / p_mse));
}

double psnr_8bit(const std::vector<cv::Mat> &p_a, const std::vector<cv::Mat> &p_b) {
	double sum = 0.0;
	double count = 0.0;
	for (size_t i = 0; i < p_a.size() && i < p_b.size(); i++) {
		cv::Mat a, b;
		p_a[i].convertTo(a, CV_64F);
		p_b[i].convertTo(b, CV_64F);
		cv::Mat d = a - b;
		sum += d.dot(d);
		count += double(d.total()) * d.channels();
	}
	return count > 0.0 ? psnr_from_mse(sum / count, 255.0) : 0.0;
}

double ssim_gray(const cv::Mat &p_a, const cv::Mat &p_b, double p_range) {
	const double c1 = (0.01 * p_range) * (0.01 * p_range);
	const double c2 = (0.03 * p_range) * (0.03 * p_range);
	cv::Mat a, b;
	p_a.convertTo(a, CV_64F);
	p_b.convertTo(b, CV_64F);
	const cv::Size window(11, 11);
	const double sigma = 1.5;
	auto blur = [&](const cv::Mat &p_in) {
		cv::Mat out;
		cv::GaussianBlur(p_in, out, window, sigma, sigma, cv::BORDER_REPLICATE);
		return out;
	};
	const cv::Mat mu_a = blur(a), mu_b = blur(b);
	const cv::Mat mu_a2 = mu_a.mul(mu_a), mu_b2 = mu_b.mul(mu_b), mu_ab = mu_a.mul(mu_b);
	const cv::Mat s_a2 = blur(a.mul(a)) - mu_a2;
	const cv::Mat s_b2 = blur(b.mul(b)) - mu_b2;
	const cv::Mat s_ab = blur(a.mul(b)) - mu_ab;
	cv::Mat num = (2.0 * mu_ab + c1).mul(2.0 * s_ab + c2);
	cv::Mat den = (mu_a2 + mu_b2 + c1).mul(s_a2 + s_b2 + c2);
	cv::Mat map;
	cv::divide(num, den, map);
	return cv::mean(map)[0];
}

static cv::Mat luminance(const cv::Mat &p_rgb) {
	cv::Mat f;
	p_rgb.convertTo(f, CV_32F);
	cv::Mat out;
	cv::transform(f, out, cv::Matx13f(0.2126f, 0.7152f, 0.0722f));
	return out;
}

namespace {

// The irradiance's luminance at 64 normals on a Fibonacci lattice.
std::vector<double> irradiance_luminance(const Cubemap &p_cubemap) {
	const ShCoefficients irradiance = convolve_cosine_lobe(project_sh(p_cubemap));
	const int count = 64;
	const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
	std::vector<double> values;
	for (int i = 0; i < count; i++) {
		const double z = 1.0 - (2.0 * i + 1.0) / count;
		const double r = std::sqrt(1.0 - z * z);
		const glm::dvec3 normal(r * std::cos(golden * i), r * std::sin(golden * i), z);
		const glm::dvec3 e = evaluate_sh(irradiance, normal);
		values.push_back(0.2126 * e.x + 0.7152 * e.y + 0.0722 * e.z);
	}
	return values;
}

double mu_law(float p_x) {
	static const double denominator = std::log1p(MU_LAW);
	const double x = std::clamp(double(p_x), 0.0, HDR_PEAK);
	return std::log1p(MU_LAW * x / HDR_PEAK) / denominator;
}

} // namespace

CubemapMetrics compare_cubemaps(const Cubemap &p_estimate, const Cubemap &p_ground_truth) {
	CubemapMetrics m;
	if (!is_valid_cubemap(p_estimate) || !is_valid_cubemap(p_ground_truth) || p_estimate.size != p_ground_truth.size) {
		return m;
	}
	std::vector<cv::Mat> est8, gt8;
	double ssim_sum = 0.0;
	double peak = 0.0;
	for (int f = 0; f < 6; f++) {
		double lo = 0.0, hi = 0.0;
		cv::minMaxLoc(p_ground_truth.faces[f].reshape(1), &lo, &hi);
		peak = std::max(peak, hi);
	}
	if (!(peak > 0.0)) {
		peak = 1.0;
	}
	double linear_sum = 0.0, linear_count = 0.0, ssim_linear_sum = 0.0, mu_sum = 0.0;
	std::vector<double> pixel_errors; // tone-mapped squared error a pixel, mean of its channels
	for (int f = 0; f < 6; f++) {
		est8.push_back(tone_map_face(p_estimate.faces[f]));
		gt8.push_back(tone_map_face(p_ground_truth.faces[f]));
		ssim_sum += ssim_gray(luminance(est8.back()), luminance(gt8.back()), 255.0);
		cv::Mat a, b;
		p_estimate.faces[f].convertTo(a, CV_64F);
		p_ground_truth.faces[f].convertTo(b, CV_64F);
		cv::Mat d = a - b;
		linear_sum += d.dot(d);
		linear_count += double(d.total()) * 3.0;
		ssim_linear_sum += ssim_gray(luminance(p_estimate.faces[f]), luminance(p_ground_truth.faces[f]), peak);
		for (int y = 0; y < p_estimate.size; y++) {
			const cv::Vec3f *e = p_estimate.faces[f].ptr<cv::Vec3f>(y);
			const cv::Vec3f *g = p_ground_truth.faces[f].ptr<cv::Vec3f>(y);
			const cv::Vec3b *e8 = est8.back().ptr<cv::Vec3b>(y);
			const cv::Vec3b *g8 = gt8.back().ptr<cv::Vec3b>(y);
			for (int x = 0; x < p_estimate.size; x++) {
				double pixel = 0.0;
				for (int c = 0; c < 3; c++) {
					const double d = mu_law(e[x][c]) - mu_law(g[x][c]);
					mu_sum += d * d;
					const double d8 = double(e8[x][c]) - double(g8[x][c]);
					pixel += d8 * d8;
				}
				pixel_errors.push_back(pixel / 3.0);
			}
		}
	}
	m.ok = true;
	m.psnr_db = psnr_8bit(est8, gt8);
	m.ssim = ssim_sum / 6.0;
	m.psnr_linear_db = psnr_from_mse(linear_sum / linear_count, peak);
	m.ssim_linear = ssim_linear_sum / 6.0;
	m.psnr_mu_db = psnr_from_mse(mu_sum / linear_count, 1.0);
	const size_t worst = std::max<size_t>(1, pixel_errors.size() / 20);
	std::nth_element(pixel_errors.begin(), pixel_errors.begin() + (pixel_errors.size() - worst), pixel_errors.end());
	double worst_sum = 0.0;
	for (size_t i = pixel_errors.size() - worst; i < pixel_errors.size(); i++) {
		worst_sum += pixel_errors[i];
	}
	m.psnr_worst5_db = psnr_from_mse(worst_sum / double(worst), 255.0);
	const std::vector<double> estimate = irradiance_luminance(p_estimate), truth = irradiance_luminance(p_ground_truth);
	double sum2 = 0.0, mean = 0.0;
	for (size_t i = 0; i < truth.size(); i++) {
		sum2 += (estimate[i] - truth[i]) * (estimate[i] - truth[i]);
		mean += truth[i];
	}
	mean /= double(truth.size());
	m.irradiance_error = mean > 0.0 ? std::sqrt(sum2 / double(truth.size())) / mean : 0.0;
	return m;
}

} // namespace roomprobe
