#include "scaramuzza.h"

#include "io/input_path.h"
#include "least_squares.h"
#include "omni_camera.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

namespace roomprobe {

namespace {

// ---------------------------------------------------------------- calib_results.txt

std::vector<std::string> split_whitespace(const std::string &p_line) {
	std::vector<std::string> tokens;
	std::istringstream stream(p_line);
	std::string token;
	while (stream >> token) {
		tokens.push_back(token);
	}
	return tokens;
}

// The whole token must be a finite number: "1.5e-3x" or "nan" is malformed.
bool parse_double(const std::string &p_token, double *r_value) {
	const char *end = p_token.data() + p_token.size();
	auto [ptr, ec] = std::from_chars(p_token.data(), end, *r_value);
	return ec == std::errc() && ptr == end && std::isfinite(*r_value);
}

bool parse_int(const std::string &p_token, int *r_value) {
	const char *end = p_token.data() + p_token.size();
	auto [ptr, ec] = std::from_chars(p_token.data(), end, *r_value);
	return ec == std::errc() && ptr == end;
}

struct DataLine {
	int number = 0; // 1-based line number in the file
	std::vector<std::string> tokens;
};

class CalibParser {
public:
	std::string path;
	std::vector<DataLine> lines;
	size_t next = 0;
	std::string error;

	// The next data line for p_field, or null with error set.
	const DataLine *take(const char *p_field, int p_last_line) {
		if (next >= lines.size()) {
			error = path + ": " + p_field + ": missing (the file ends at line " + std::to_string(p_last_line) + ")";
			return nullptr;
		}
		return &lines[next++];
	}

	std::string where(const DataLine &p_line, const char *p_field) const {
		return path + ":" + std::to_string(p_line.number) + ": " + p_field + ": ";
	}

	// A count followed by exactly that many coefficients.
	bool read_polynomial(const char *p_field, int p_last_line, std::vector<double> *r_coefficients) {
		const DataLine *line = take(p_field, p_last_line);
		if (!line) {
			return false;
		}
		int count = 0;
		if (!parse_int(line->tokens[0], &count)) {
			error = where(*line, p_field) + "the count '" + line->tokens[0] + "' is not an integer";
			return false;
		}
		if (count < 1 || count > 64) {
			error = where(*line, p_field) + "the count " + std::to_string(count) + " is not between 1 and 64";
			return false;
		}
		const int found = int(line->tokens.size()) - 1;
		if (found != count) {
			error = where(*line, p_field) + "the count says " + std::to_string(count) + " coefficients but the line has " + std::to_string(found);
			return false;
		}
		r_coefficients->assign(count, 0.0);
		for (int i = 0; i < count; i++) {
			if (!parse_double(line->tokens[i + 1], &(*r_coefficients)[i])) {
				error = where(*line, p_field) + "coefficient " + std::to_string(i) + " '" + line->tokens[i + 1] + "' is not a finite number";
				return false;
			}
		}
		return true;
	}

	bool read_numbers(const char *p_field, int p_last_line, int p_count, double *r_values) {
		const DataLine *line = take(p_field, p_last_line);
		if (!line) {
			return false;
		}
		if (int(line->tokens.size()) != p_count) {
			error = where(*line, p_field) + "expected " + std::to_string(p_count) + " numbers, found " + std::to_string(line->tokens.size());
			return false;
		}
		for (int i = 0; i < p_count; i++) {
			if (!parse_double(line->tokens[i], &r_values[i])) {
				error = where(*line, p_field) + "value " + std::to_string(i) + " '" + line->tokens[i] + "' is not a finite number";
				return false;
			}
		}
		return true;
	}
};

double polynomial(const std::vector<double> &p_coefficients, double p_x) {
	double value = 0.0;
	for (size_t i = p_coefficients.size(); i-- > 0;) {
		value = value * p_x + p_coefficients[i];
	}
	return value;
}

// ---------------------------------------------------------------- the fit

// The fitted unknowns, in this order in the parameter vector.
enum FitParam { XI, FX, FY, CX, CY, SKEW, K1, K2, P1, P2, ROLL, FIT_PARAM_COUNT };

glm::dmat3 rotation_z(double p_angle) {
	const double c = std::cos(p_angle), s = std::sin(p_angle);
	// glm is column-major: columns (c, s, 0), (-s, c, 0), (0, 0, 1).
	return glm::dmat3(c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0);
}

OmniParams unpack(const double *p_values, const OmniParams &p_base) {
	OmniParams params = p_base;
	params.xi = p_values[XI];
	params.fx = p_values[FX];
	params.fy = p_values[FY];
	params.cx = p_values[CX];
	params.cy = p_values[CY];
	params.skew = p_values[SKEW];
	params.k1 = p_values[K1];
	params.k2 = p_values[K2];
	params.p1 = p_values[P1];
	params.p2 = p_values[P2];
	return params;
}

struct Sample {
	glm::dvec2 pixel;
	glm::dvec3 ray; // OCamCalib's ray, OpenCV's frame
};

std::vector<Sample> sample_circle(const ScaramuzzaModel &p_model, const glm::dvec2 &p_centre, double p_radius, double p_step, bool p_rim) {
	std::vector<Sample> samples;
	auto inside = [&](const glm::dvec2 &p) {
		const bool in_image = p.x >= -0.5 && p.x <= p_model.width - 0.5 && p.y >= -0.5 && p.y <= p_model.height - 0.5;
		return in_image && (p_radius <= 0.0 || glm::length(p - p_centre) <= p_radius);
	};
	for (double y = 0.0; y <= p_model.height - 1; y += p_step) {
		for (double x = 0.0; x <= p_model.width - 1; x += p_step) {
			if (inside({ x, y })) {
				samples.push_back({ { x, y }, unproject_scaramuzza(p_model, { x, y }) });
			}
		}
	}
	// The rim, where the model bends most, weighs as much as its length in grid steps.
	if (p_rim && p_radius > 0.0) {
		const int count = std::max(8, int(2.0 * std::numbers::pi * p_radius / p_step));
		for (int i = 0; i < count; i++) {
			const double angle = 2.0 * std::numbers::pi * i / count;
			const glm::dvec2 p = p_centre + (p_radius - 1e-9) * glm::dvec2(std::cos(angle), std::sin(angle));
			if (inside(p)) {
				samples.push_back({ p, unproject_scaramuzza(p_model, p) });
			}
		}
	}
	return samples;
}

// One stage of the fit: the p_free entries of r_values moved to project p_samples' rays onto their
// pixels (the others held). False when the least squares fail.
bool fit_stage(const std::vector<Sample> &p_samples, const OmniParams &p_base, const std::vector<int> &p_free, double *r_values) {
	std::vector<double> params;
	for (int index : p_free) {
		params.push_back(r_values[index]);
	}
	auto residuals = [&](const std::vector<double> &p_params, std::vector<double> &r_residuals) {
		double values[FIT_PARAM_COUNT];
		std::copy(r_values, r_values + FIT_PARAM_COUNT, values);
		for (size_t i = 0; i < p_free.size(); i++) {
			values[p_free[i]] = p_params[i];
		}
		const OmniParams params = unpack(values, p_base);
		const glm::dmat3 rotation = rotation_z(values[ROLL]);
		r_residuals.resize(2 * p_samples.size());
		for (size_t i = 0; i < p_samples.size(); i++) {
			glm::dvec2 pixel;
			if (!project_omni(params, rotation * p_samples[i].ray, &pixel)) {
				return false;
			}
			r_residuals[2 * i] = pixel.x - p_samples[i].pixel.x;
			r_residuals[2 * i + 1] = pixel.y - p_samples[i].pixel.y;
		}
		return true;
	};
	LeastSquaresOptions options;
	options.max_iterations = 300;
	const LeastSquaresResult fitted = minimize_least_squares(residuals, params, options);
	for (size_t i = 0; i < p_free.size(); i++) {
		r_values[p_free[i]] = params[i];
	}
	return fitted.ok;
}

// Errors over a dense grid of the image circle, with the same unrestricted model, into r_result
// (eval_count, max_px, rms_px). False, error set, when a ray does not project.
bool measure_fit(const ScaramuzzaModel &p_model, const glm::dvec2 &p_centre, const OmniFitOptions &p_options, OmniFitResult *r_result) {
	OmniFitResult &result = *r_result;
	double sum = 0.0;
	for (const Sample &sample : sample_circle(p_model, p_centre, p_options.circle_radius, p_options.eval_step_px, true)) {
		glm::dvec2 pixel;
		if (!project_omni(result.params, result.omni_from_scaramuzza * sample.ray, &pixel)) {
			result.error = "fit_omni_to_scaramuzza: the fitted model cannot project a ray of the image circle";
			return false;
		}
		const double error = glm::length(pixel - sample.pixel);
		sum += error * error;
		result.max_px = std::max(result.max_px, error);
		result.eval_count++;
	}
	result.rms_px = std::sqrt(sum / std::max(1, result.eval_count));
	return true;
}

// What the lens sees: the image circle (or the whole image), up to its largest angle.
void set_field_of_view(const ScaramuzzaModel &p_model, const glm::dvec2 &p_centre, double p_circle_radius, OmniParams *r_params) {
	OmniParams &params = *r_params;
	double max_angle = 0.0;
	if (p_circle_radius > 0.0) {
		params.circle_cx = p_centre.x;
		params.circle_cy = p_centre.y;
		params.circle_radius = p_circle_radius;
		for (int i = 0; i < 3600; i++) {
			const double angle = 2.0 * std::numbers::pi * i / 3600.0;
			const glm::dvec3 ray = unproject_scaramuzza(p_model, p_centre + p_circle_radius * glm::dvec2(std::cos(angle), std::sin(angle)));
			max_angle = std::max(max_angle, std::acos(std::clamp(ray.z, -1.0, 1.0)));
		}
	} else {
		for (const Sample &sample : sample_circle(p_model, p_centre, 0.0, 1.0, false)) {
			max_angle = std::max(max_angle, std::acos(std::clamp(sample.ray.z, -1.0, 1.0)));
		}
	}
	params.max_angle_deg = max_angle * 180.0 / std::numbers::pi;
}

} // namespace

ScaramuzzaLoadResult load_ocamcalib(const std::string &p_path) {
	ScaramuzzaLoadResult result;
	result.error = input_file_problem(p_path, "no such file");
	if (!result.error.empty()) {
		return result;
	}
	std::ifstream file(p_path);
	if (!file) {
		result.error = p_path + ": cannot open the file";
		return result;
	}
	CalibParser parser;
	parser.path = p_path;
	std::string text;
	int line_number = 0;
	while (std::getline(file, text)) {
		line_number++;
		const size_t first = text.find_first_not_of(" \t\r");
		if (first == std::string::npos || text[first] == '#') {
			continue;
		}
		parser.lines.push_back({ line_number, split_whitespace(text) });
	}
	ScaramuzzaModel &model = result.model;
	double centre[2], affine[3];
	if (!parser.read_polynomial("ss", line_number, &model.ss) || !parser.read_polynomial("invpol", line_number, &model.invpol) ||
			!parser.read_numbers("center", line_number, 2, centre) || !parser.read_numbers("affine", line_number, 3, affine)) {
		result.error = parser.error;
		return result;
	}
	model.xc = centre[0];
	model.yc = centre[1];
	model.c = affine[0];
	model.d = affine[1];
	model.e = affine[2];
	const DataLine *size = parser.take("image size", line_number);
	if (!size) {
		result.error = parser.error;
		return result;
	}
	if (size->tokens.size() != 2 || !parse_int(size->tokens[0], &model.height) || !parse_int(size->tokens[1], &model.width) ||
			model.height <= 0 || model.width <= 0) {
		result.error = parser.where(*size, "image size") + "expected two positive integers, height and width";
		return result;
	}
	// cam2world divides by the affine's determinant; ss(0) = 0 would make the centre's ray
	// vanish.
	if (std::abs(model.c - model.d * model.e) < 1e-9) {
		result.error = p_path + ": affine: c - d * e is zero, the affine is singular";
		return result;
	}
	if (model.ss[0] == 0.0) {
		result.error = p_path + ": ss: the constant coefficient a0 is zero";
		return result;
	}
	result.ok = true;
	return result;
}

bool project_scaramuzza(const ScaramuzzaModel &p_model, const glm::dvec3 &p_point, glm::dvec2 *r_pixel) {
	// To OCamCalib's frame (see the header).
	const double x = p_point.y, y = p_point.x, z = -p_point.z;
	const double norm = std::hypot(x, y);
	if (!std::isfinite(norm) || !std::isfinite(z)) {
		return false;
	}
	if (norm == 0.0) {
		if (!(z < 0.0)) {
			return false; // the zero vector, or straight behind
		}
		*r_pixel = { p_model.yc, p_model.xc };
		return true;
	}
	const double theta = std::atan(z / norm); // -pi/2 on the optical axis, 0 at 90 degrees off it
	const double rho = polynomial(p_model.invpol, theta);
	if (!(rho >= 0.0)) {
		return false;
	}
	const double u = x / norm * rho, v = y / norm * rho;
	const double row = u * p_model.c + v * p_model.d + p_model.xc;
	const double column = u * p_model.e + v + p_model.yc;
	*r_pixel = { column, row };
	return true;
}

glm::dvec3 unproject_scaramuzza(const ScaramuzzaModel &p_model, const glm::dvec2 &p_pixel) {
	const double row = p_pixel.y - p_model.xc, column = p_pixel.x - p_model.yc;
	const double inverse_determinant = 1.0 / (p_model.c - p_model.d * p_model.e);
	const double x = inverse_determinant * (row - p_model.d * column);
	const double y = inverse_determinant * (-p_model.e * row + p_model.c * column);
	const double z = polynomial(p_model.ss, std::hypot(x, y));
	// Back from OCamCalib's frame (see the header).
	return glm::normalize(glm::dvec3(y, x, -z));
}

OmniFitResult fit_omni_to_scaramuzza(const ScaramuzzaModel &p_model, const OmniFitOptions &p_options) {
	OmniFitResult result;
	if (p_model.width <= 0 || p_model.height <= 0 || p_model.ss.empty() || p_model.invpol.empty()) {
		result.error = "fit_omni_to_scaramuzza: the OCamCalib model is empty";
		return result;
	}
	if (!(p_options.sample_step_px > 0.0) || !(p_options.eval_step_px > 0.0)) {
		result.error = "fit_omni_to_scaramuzza: sample_step_px and eval_step_px must be positive";
		return result;
	}
	const glm::dvec2 centre = p_options.circle_cx < 0.0 || p_options.circle_cy < 0.0 ? glm::dvec2(p_model.yc, p_model.xc)
																					  : glm::dvec2(p_options.circle_cx, p_options.circle_cy);
	const std::vector<Sample> samples = sample_circle(p_model, centre, p_options.circle_radius, p_options.sample_step_px, true);
	if (samples.size() < 64) {
		result.error = "fit_omni_to_scaramuzza: too few pixels inside the image circle (" + std::to_string(samples.size()) + ")";
		return result;
	}

	// While fitting, the model must project every ray: no circle, no angle limit.
	OmniParams base;
	base.width = p_model.width;
	base.height = p_model.height;

	// Start from an equidistant-like lens: near the axis OCamCalib gives rho ~ |a0| theta and the
	// unified model with xi = 1 gives r ~ f theta / 2.
	const double a0 = std::abs(p_model.ss[0]);
	double start[FIT_PARAM_COUNT] = {};
	start[XI] = 1.0;
	start[FX] = 2.0 * a0;
	start[FY] = 2.0 * a0 * p_model.c;
	start[CX] = p_model.yc;
	start[CY] = p_model.xc;

	// First the lens without distortion, then everything: the distortion terms and xi are nearly
	// interchangeable near the axis, so they start from a sensible lens.
	std::vector<int> free = { XI, FX, FY, CX, CY, ROLL };
	if (!fit_stage(samples, base, free, start)) {
		result.error = "fit_omni_to_scaramuzza: the starting lens cannot project the samples";
		return result;
	}
	if (p_options.fit_skew) {
		free.push_back(SKEW);
	}
	if (p_options.fit_distortion) {
		free.insert(free.end(), { K1, K2, P1, P2 });
	}
	if (!fit_stage(samples, base, free, start)) {
		result.error = "fit_omni_to_scaramuzza: the fit failed";
		return result;
	}

	result.params = unpack(start, base);
	result.roll_rad = start[ROLL];
	result.omni_from_scaramuzza = rotation_z(start[ROLL]);
	result.sample_count = int(samples.size());

	if (!measure_fit(p_model, centre, p_options, &result)) {
		return result;
	}
	set_field_of_view(p_model, centre, p_options.circle_radius, &result.params);
	result.ok = true;
	return result;
}

} // namespace roomprobe
