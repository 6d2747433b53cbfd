#include "trajectory.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <string_view>
#include <system_error>

namespace roomprobe {

namespace {

// The shortest text that reads back as the same double (for files and messages alike).
std::string format_double(double p_value) {
	std::array<char, 64> buffer;
	const std::to_chars_result result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), p_value);
	return std::string(buffer.data(), result.ptr);
}

// Checks one sample, normalising its rotation; p_where prefixes the error ("sample 3", "line 7").
bool check_sample(TimedPose *r_sample, const std::string &p_where, double p_unit_tolerance, std::string *r_error) {
	if (!std::isfinite(r_sample->t_s)) {
		*r_error = p_where + ": timestamp is not finite";
		return false;
	}
	if (!is_finite(r_sample->world_from_camera)) {
		*r_error = p_where + ": pose is not finite";
		return false;
	}
	if (!normalize_rotation(&r_sample->world_from_camera.rotation, p_unit_tolerance)) {
		*r_error = p_where + ": rotation is not a unit quaternion (norm " +
				format_double(glm::length(r_sample->world_from_camera.rotation)) + ")";
		return false;
	}
	return true;
}

} // namespace

bool Trajectory::set_samples(std::vector<TimedPose> p_samples, std::string *r_error) {
	for (size_t i = 0; i < p_samples.size(); i++) {
		const std::string where = "sample " + std::to_string(i);
		if (!check_sample(&p_samples[i], where, UNIT_TOLERANCE, r_error)) {
			return false;
		}
		// Strictly increasing: two poses at one instant leave the interpolation undefined.
		if (i > 0 && !(p_samples[i].t_s > p_samples[i - 1].t_s)) {
			*r_error = where + ": timestamp " + format_double(p_samples[i].t_s) + " s is not after sample " +
					std::to_string(i - 1) + "'s (" + format_double(p_samples[i - 1].t_s) + " s)";
			return false;
		}
	}
	samples = std::move(p_samples);
	return true;
}

bool Trajectory::append(const TimedPose &p_sample, std::string *r_error) {
	TimedPose sample = p_sample;
	const std::string where = "sample " + std::to_string(samples.size());
	if (!check_sample(&sample, where, UNIT_TOLERANCE, r_error)) {
		return false;
	}
	if (!samples.empty() && !(sample.t_s > samples.back().t_s)) {
		*r_error = where + ": timestamp " + format_double(sample.t_s) + " s is not after the last sample's (" +
				format_double(samples.back().t_s) + " s)";
		return false;
	}
	samples.push_back(sample);
	return true;
}

bool Trajectory::pose_at(double p_t_s, Pose *r_pose, std::string *r_error, double p_extrapolation_tolerance_s) const {
	if (samples.empty()) {
		*r_error = "no pose at t = " + format_double(p_t_s) + " s: the trajectory is empty";
		return false;
	}
	if (!std::isfinite(p_t_s)) {
		*r_error = "no pose at t = " + format_double(p_t_s) + " s: the time is not finite";
		return false;
	}
	const double tolerance = std::isfinite(p_extrapolation_tolerance_s) ? std::max(p_extrapolation_tolerance_s, 0.0) : 0.0;
	const double start = samples.front().t_s;
	const double end = samples.back().t_s;
	if (p_t_s < start - tolerance || p_t_s > end + tolerance) {
		*r_error = "no pose at t = " + format_double(p_t_s) + " s: outside the trajectory [" + format_double(start) +
				", " + format_double(end) + "] s";
		if (tolerance > 0.0) {
			*r_error += " and the extrapolation tolerance (" + format_double(tolerance) + " s)";
		}
		return false;
	}
	if (samples.size() == 1) {
		*r_pose = samples.front().world_from_camera; // no velocity to extrapolate with
		return true;
	}
	// The pair [i - 1, i] around p_t_s; before the start or after the end, the first or last pair.
	const auto after = std::upper_bound(samples.begin(), samples.end(), p_t_s,
			[](double p_t, const TimedPose &p_sample) { return p_t < p_sample.t_s; });
	size_t i = static_cast<size_t>(after - samples.begin());
	i = std::clamp<size_t>(i, 1, samples.size() - 1);
	const TimedPose &from = samples[i - 1];
	const TimedPose &to = samples[i];
	if (p_t_s == to.t_s) {
		*r_pose = to.world_from_camera; // the last sample itself, exactly
		return true;
	}
	const double alpha = (p_t_s - from.t_s) / (to.t_s - from.t_s);
	*r_pose = interpolate(from.world_from_camera, to.world_from_camera, alpha);
	return true;
}

// ---------------------------------------------------------------------------------- TUM files

namespace {

// Splits on spaces and tabs.
std::vector<std::string_view> split_fields(std::string_view p_line) {
	std::vector<std::string_view> fields;
	size_t i = 0;
	while (i < p_line.size()) {
		while (i < p_line.size() && (p_line[i] == ' ' || p_line[i] == '\t')) {
			i++;
		}
		const size_t begin = i;
		while (i < p_line.size() && p_line[i] != ' ' && p_line[i] != '\t') {
			i++;
		}
		if (i > begin) {
			fields.push_back(p_line.substr(begin, i - begin));
		}
	}
	return fields;
}

// A whole field as a double (locale-independent, unlike strtod); false on any trailing junk.
bool parse_double(std::string_view p_text, double *r_value) {
	if (!p_text.empty() && p_text.front() == '+') {
		p_text.remove_prefix(1);
	}
	const char *end = p_text.data() + p_text.size();
	const std::from_chars_result result = std::from_chars(p_text.data(), end, *r_value);
	// Out of range ("1e999") is reported as not a number too: it cannot be a pose.
	return result.ec == std::errc() && result.ptr == end && !p_text.empty();
}

// The field as text for an error message, with unprintable bytes as \xNN so they show.
std::string quote_field(std::string_view p_field) {
	static const char *const hex = "0123456789abcdef";
	std::string text = "'";
	for (const char c : p_field) {
		const unsigned char byte = static_cast<unsigned char>(c);
		if (byte >= 0x20 && byte < 0x7f) {
			text += c;
		} else {
			text += "\\x";
			text += hex[byte >> 4];
			text += hex[byte & 15];
		}
	}
	return text + "'";
}

} // namespace

TrajectoryLoadResult load_tum_trajectory(const std::string &p_path) {
	TrajectoryLoadResult result;
	std::ifstream file(p_path);
	if (!file) {
		result.error = p_path + ": cannot open the trajectory file";
		return result;
	}
	static const char *const names[8] = { "timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw" };
	std::vector<TimedPose> samples;
	std::string line;
	int line_number = 0;
	int previous_line = 0;
	while (std::getline(file, line)) {
		line_number++;
		const std::string where = p_path + ":" + std::to_string(line_number);
		if (!line.empty() && line.back() == '\r') {
			line.pop_back();
		}
		const std::vector<std::string_view> fields = split_fields(line);
		if (fields.empty() || fields.front().front() == '#') {
			continue;
		}
		if (fields.size() != 8) {
			result.error = where + ": expected 8 fields (timestamp tx ty tz qx qy qz qw), got " +
					std::to_string(fields.size());
			return result;
		}
		double values[8];
		for (int i = 0; i < 8; i++) {
			if (!parse_double(fields[i], &values[i])) {
				result.error = where + ": " + names[i] + ": not a number (" + quote_field(fields[i]) + ")";
				return result;
			}
			if (!std::isfinite(values[i])) {
				result.error = where + ": " + names[i] + ": not finite (" + quote_field(fields[i]) + ")";
				return result;
			}
		}
		TimedPose sample;
		sample.t_s = values[0];
		sample.world_from_camera.translation = glm::dvec3(values[1], values[2], values[3]);
		sample.world_from_camera.rotation = glm::dquat(values[7], values[4], values[5], values[6]); // (w, x, y, z)
		std::string error;
		if (!check_sample(&sample, where, TUM_UNIT_TOLERANCE, &error)) {
			result.error = error;
			return result;
		}
		if (!samples.empty() && !(sample.t_s > samples.back().t_s)) {
			result.error = where + ": timestamp " + std::string(fields[0]) + " is not after the previous pose's (" +
					format_double(samples.back().t_s) + ", line " + std::to_string(previous_line) + ")";
			return result;
		}
		samples.push_back(sample);
		previous_line = line_number;
	}
	if (file.bad()) {
		result.error = p_path + ": read error after line " + std::to_string(line_number);
		return result;
	}
	if (samples.empty()) {
		result.error = p_path + ": no poses (expected lines 'timestamp tx ty tz qx qy qz qw')";
		return result;
	}
	std::string error;
	if (!result.trajectory.set_samples(std::move(samples), &error)) {
		result.error = p_path + ": " + error; // unreachable: every line was checked above
		return result;
	}
	result.ok = true;
	return result;
}

std::string save_tum_trajectory(const std::string &p_path, const Trajectory &p_trajectory, const std::vector<std::string> &p_header) {
	TumTrajectoryWriter writer;
	std::string error = writer.open(p_path, p_header);
	for (size_t i = 0; error.empty() && i < p_trajectory.size(); i++) {
		error = writer.add_pose(p_trajectory.get_samples()[i]);
	}
	const std::string closed = writer.close();
	return error.empty() ? closed : error;
}

std::string TumTrajectoryWriter::open(const std::string &p_path, const std::vector<std::string> &p_header) {
	close();
	path = p_path;
	error.clear();
	has_last = false;
	file.clear();
	error = replacement.begin(p_path);
	if (!error.empty()) {
		return error;
	}
	file.open(replacement.temp_path(), std::ios::out | std::ios::trunc | std::ios::binary);
	if (!file) {
		error = p_path + ": cannot be opened for writing";
		replacement.discard();
		return error;
	}
	for (const std::string &line : p_header) {
		add_comment(line);
	}
	return write("# timestamp tx ty tz qx qy qz qw\n");
}

std::string TumTrajectoryWriter::add_pose(const TimedPose &p_sample) {
	if (!error.empty() || !file.is_open()) {
		return error.empty() ? "TumTrajectoryWriter::add_pose: no file is open" : error;
	}
	TimedPose sample = p_sample;
	std::string problem;
	if (!check_sample(&sample, path + ": pose at " + format_double(p_sample.t_s), Trajectory::UNIT_TOLERANCE, &problem)) {
		return problem; // this pose is left out; the file stays good
	}
	if (has_last && !(sample.t_s > last_t_s)) {
		return path + ": timestamp " + format_double(sample.t_s) + " is not after the previous pose's (" + format_double(last_t_s) + ")";
	}
	const glm::dquat &q = sample.world_from_camera.rotation;
	const glm::dvec3 &t = sample.world_from_camera.translation;
	const double values[8] = { sample.t_s, t.x, t.y, t.z, q.x, q.y, q.z, q.w };
	std::string line;
	for (int i = 0; i < 8; i++) {
		line += (i ? " " : "") + format_double(values[i]);
	}
	has_last = true;
	last_t_s = sample.t_s;
	return write(line + "\n");
}

std::string TumTrajectoryWriter::add_comment(const std::string &p_text) {
	std::string text;
	size_t start = 0;
	while (true) {
		const size_t end = p_text.find('\n', start);
		text += "# " + p_text.substr(start, end == std::string::npos ? std::string::npos : end - start) + "\n";
		if (end == std::string::npos) {
			break;
		}
		start = end + 1;
	}
	return write(text);
}

std::string TumTrajectoryWriter::write(const std::string &p_text) {
	if (!error.empty() || !file.is_open()) {
		return error.empty() ? "TumTrajectoryWriter: no file is open" : error;
	}
	file << p_text;
	if (!file) {
		error = path + ": write error";
	}
	return error;
}

std::string TumTrajectoryWriter::close() {
	if (!file.is_open()) {
		return error;
	}
	file.close();
	if (!file && error.empty()) {
		error = path + ": write error";
	}
	if (!error.empty()) {
		replacement.discard(); // the path stays as it was
		return error;
	}
	error = replacement.commit();
	return error;
}

} // namespace roomprobe
