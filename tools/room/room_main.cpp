// roomprobe_room: the room a recording's sweep shows (issue #18): the world frame, the floorplan,
// the ceiling height (engine/room_sweep.h), written as a room.yaml, with a picture of the
// floorplan over the dense model seen from above. When the recording holds its true room, the
// two are compared, and the true floorplan is registered to the reconstructed walls as a given
// floorplan would be; the last line is
//   corner_error_max_m=... ceiling_error_m=... up_error_deg=... registration_error_m=... registration_rms_m=... corner_error_fitted_m=...
// (corner_error_max_m through the first camera, so with the tracker's drift; corner_error_fitted_m
// after the best turn and shift in the floor plane: the room's shape alone).
//
// roomprobe_room --recording DIR --out FILE [--picture FILE] [--true-poses] [--seconds S] [--force] [--quiet]

#include <io/image_codec.h>
#include <engine/room_sweep.h>
#include <recording/room_file.h>

#include "../common/cli.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>

namespace {

using namespace roomprobe;

// Seen from above (x to the right, z down the picture, as Godot's top view), 1 px = 1 cm: the
// dense surface shaded by height, the camera's path (blue), the true floorplan (green) and the
// one found (red), all in the found world frame.
cv::Mat top_view(const RoomSweepResult &p_result) {
	const Floorplan &found = p_result.estimate.floorplan;
	std::vector<std::vector<Vec2>> outlines;
	if (!found.points.empty()) {
		outlines.push_back(found.points);
	}
	const Pose found_from_true = compose(p_result.world_from_model, inverse(p_result.true_world_from_model));
	std::vector<Vec2> truth;
	if (p_result.has_truth) {
		for (const Vec2 &p : p_result.truth.floorplan.points) {
			const glm::dvec3 q = transform_point(found_from_true, glm::dvec3(p.x, 0.0, p.y));
			truth.push_back({ q.x, q.z });
		}
		outlines.push_back(truth);
	}
	const std::vector<SurfaceSample> world = transform_samples(p_result.samples, p_result.world_from_model);
	double min_x = 1e9, min_z = 1e9, max_x = -1e9, max_z = -1e9;
	auto grow = [&](double p_x, double p_z) {
		min_x = std::min(min_x, p_x);
		max_x = std::max(max_x, p_x);
		min_z = std::min(min_z, p_z);
		max_z = std::max(max_z, p_z);
	};
	for (const auto &outline : outlines) {
		for (const Vec2 &p : outline) {
			grow(p.x, p.y);
		}
	}
	if (outlines.empty()) {
		for (const SurfaceSample &s : world) {
			grow(s.position_m.x, s.position_m.z);
		}
	}
	if (!(max_x > min_x)) {
		return cv::Mat();
	}
	constexpr double PX_PER_M = 100.0, MARGIN_M = 0.5;
	const int width = int(std::min(4000.0, (max_x - min_x + 2 * MARGIN_M) * PX_PER_M));
	const int height = int(std::min(4000.0, (max_z - min_z + 2 * MARGIN_M) * PX_PER_M));
	auto pixel = [&](double p_x, double p_z) { return cv::Point(int((p_x - min_x + MARGIN_M) * PX_PER_M), int((p_z - min_z + MARGIN_M) * PX_PER_M)); };
	cv::Mat picture(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
	for (const SurfaceSample &s : world) { // darker the higher: walls dark, floor light
		const cv::Point p = pixel(s.position_m.x, s.position_m.z);
		if (p.x >= 0 && p.y >= 0 && p.x < width && p.y < height) {
			const int shade = std::clamp(int(220.0 - 60.0 * s.position_m.y), 40, 220);
			cv::Vec3b &c = picture.at<cv::Vec3b>(p);
			c = cv::Vec3b(uint8_t(std::min<int>(c[0], shade)), uint8_t(std::min<int>(c[1], shade)), uint8_t(std::min<int>(c[2], shade)));
		}
	}
	auto draw = [&](const std::vector<Vec2> &p_outline, const cv::Scalar &p_bgr, int p_thickness) {
		std::vector<cv::Point> points;
		for (const Vec2 &p : p_outline) {
			points.push_back(pixel(p.x, p.y));
		}
		cv::polylines(picture, std::vector<std::vector<cv::Point>>{ points }, true, p_bgr, p_thickness, cv::LINE_AA);
	};
	if (!truth.empty()) {
		draw(truth, cv::Scalar(60, 170, 60), 5);
	}
	if (!found.points.empty()) {
		draw(found.points, cv::Scalar(40, 40, 220), 2);
	}
	return picture;
}

// The usage, after p_error when there is one; usage's exit status.
int usage(const char *p_error) {
	std::fprintf(stderr,
			"%s%susage: roomprobe_room --recording DIR --out FILE [--picture FILE] [--true-poses] [--seconds S]\n"
			"                      [--force] [--quiet]\n"
			"  --out FILE: the room.yaml to write (an existing file is kept unless --force)\n"
			"  --picture FILE: the top view (default: FILE with .png; the same rule); never a folder or a device\n"
			"  --true-poses: fuse depth at the recording's true poses instead of tracking\n"
			"  --seconds S: only the sweep's first S seconds\n",
			p_error ? "roomprobe_room: " : "", p_error ? (std::string(p_error) + "\n").c_str() : "");
	return 2;
}

// The command line, as given.
struct RoomArgs {
	RoomSweepOptions options;
	std::string out, picture_path;
	bool force = false, quiet = false;
};

// The command line into *r_args: the exit status when the tool ends here (--help, a bad option),
// else nothing.
std::optional<int> parse_arguments(int argc, char **argv, RoomArgs *r_args) {
	cli::Arguments cursor(argc, argv, 1);
	std::string arg;
	while (cursor.next(&arg)) {
		double x = 0.0;
		if (arg == "--recording") {
			if (!cursor.value(&r_args->options.recording)) {
				return usage("--recording needs a folder");
			}
		} else if (arg == "--out") {
			if (!cursor.value(&r_args->out)) {
				return usage("--out needs a file name");
			}
		} else if (arg == "--picture") {
			if (!cursor.value(&r_args->picture_path)) {
				return usage("--picture needs a file name");
			}
		} else if (arg == "--seconds") {
			if (!cursor.positive_number(36000.0, &x)) {
				return usage("--seconds needs a number of seconds in (0, 36000]");
			}
			r_args->options.max_seconds = x;
		} else if (arg == "--true-poses") {
			r_args->options.true_poses = true;
		} else if (arg == "--force") {
			r_args->force = true;
		} else if (arg == "--quiet") {
			r_args->quiet = true;
		} else if (arg == "--help" || arg == "-h") {
			usage(nullptr);
			return 0;
		} else {
			return usage(("unknown argument " + arg).c_str());
		}
	}
	return std::nullopt;
}

// Why p_option's file p_path cannot be written, or "": never into the recording it reads (--out
// REC/room.yaml would replace the recording's own room), even with --force, as bench's
// --save-trajectory; a device (/dev/full) is refused even with --force: it was once removed when
// the write failed.
std::string output_problem(const char *p_option, const std::string &p_path, const RoomArgs &p_args) {
	const std::string problem = cli::output_in_input_problem(p_option, p_path, { p_args.options.recording });
	return problem.empty() ? cli::output_file_problem(p_option, p_path, p_args.force) : problem;
}

// The options checked before the sweep: both given, and the room and the picture (named when not
// given) writable; the exit status when they are not, else nothing.
std::optional<int> check_outputs(RoomArgs *r_args) {
	const std::string &out = r_args->out;
	std::string &picture_path = r_args->picture_path;
	if (r_args->options.recording.empty() || out.empty()) {
		return usage("--recording and --out are required");
	}
	std::error_code ec;
	if (std::filesystem::is_directory(out, ec)) {
		return usage(("--out " + out + " is a folder: name the room.yaml to write").c_str());
	}
	std::string problem = output_problem("--out", out, *r_args);
	if (!problem.empty()) {
		return usage(problem.c_str());
	}
	if (picture_path.empty()) {
		picture_path = std::filesystem::path(out).replace_extension(".png").string();
	}
	if (std::filesystem::path(picture_path).lexically_normal() == std::filesystem::path(out).lexically_normal()) {
		return usage(("the picture and the room would both be " + out + ": give --picture another name").c_str());
	}
	problem = output_problem("the picture", picture_path, *r_args);
	if (!problem.empty()) {
		return usage(problem.c_str());
	}
	// A folder that cannot be written (read-only, say) is refused now, not after the sweep.
	problem = cli::output_file_unwritable("--out", out);
	if (problem.empty()) {
		problem = cli::output_file_unwritable("the picture", picture_path);
	}
	if (!problem.empty()) {
		return usage(problem.c_str());
	}
	return std::nullopt;
}

// What the sweep found: the floor, the corners, the walls, the ceiling and the fisheye's searches.
void print_estimate(const RoomSweepResult &p_result) {
	const RoomEstimate &estimate = p_result.estimate;
	std::printf("room: %s: %s\n", room_estimate_state_name(estimate.state), estimate.message.c_str());
	std::printf("floor: %.2f m2 seen, %.1f mm rms\n", estimate.floor_seen_m2, estimate.floor_rms_m * 1000.0);
	for (size_t i = 0; i < estimate.floorplan.points.size(); i++) {
		const Vec2 &p = estimate.floorplan.points[i];
		std::printf("corner %zu: (%.3f, %.3f) m; edge %zu seen %.0f%%\n", i, p.x, p.y, i,
				100.0 * (i < estimate.edge_confidence.size() ? estimate.edge_confidence[i] : 0.0));
	}
	for (const WallEstimate &wall : estimate.walls) {
		std::printf("wall: normal (%.3f, %.3f), at %.3f m, seen from %.2f to %.2f m along it, %.2f m2, %.1f mm rms\n", wall.normal.x, wall.normal.y,
				wall.offset_m, wall.from_m, wall.to_m, wall.area_m2, wall.rms_m * 1000.0);
	}
	if (estimate.floorplan.ceiling_height_m > 0.0) {
		std::printf("ceiling: %.3f m (%s)\n", estimate.floorplan.ceiling_height_m, estimate.ceiling_source.c_str());
	}
	if (!p_result.fisheye_ceiling.message.empty()) {
		std::printf("fisheye ceiling search: %s (%zu views)\n", p_result.fisheye_ceiling.message.c_str(), p_result.fisheye_ceiling.views_used);
	}
	for (const std::string &line : p_result.fisheye_walls) {
		std::printf("fisheye wall search: %s\n", line.c_str());
	}
}

// The picture (when there is one to draw) and the room.yaml written: 0, or 1 when either fails or
// no room was found.
int write_outputs(const RoomArgs &p_args, const RoomSweepResult &p_result) {
	const cv::Mat picture = top_view(p_result);
	if (!picture.empty()) {
		const std::string written = png_write(p_args.picture_path, picture);
		if (!written.empty()) {
			std::fprintf(stderr, "roomprobe_room: %s\n", written.c_str());
			return 1;
		}
		std::printf("picture: %s\n", p_args.picture_path.c_str());
	}
	if (p_result.room.floorplan.points.empty()) {
		std::fprintf(stderr, "roomprobe_room: %s: no room written: %s\n", p_args.options.recording.c_str(), p_result.estimate.message.c_str());
		return 1;
	}
	const std::string saved = save_room_file(p_args.out, p_result.room);
	if (!saved.empty()) {
		std::fprintf(stderr, "roomprobe_room: %s\n", saved.c_str());
		return 1;
	}
	std::printf("room.yaml: %s\n", p_args.out.c_str());
	return 0;
}

// The room found against the recording's true room, and the true floorplan registered to the
// reconstructed walls; the last line.
void print_comparison(const RoomSweepResult &p_result) {
	const RoomComparison comparison =
			compare_rooms(p_result.estimate.floorplan, p_result.world_from_model, p_result.truth.floorplan, p_result.true_world_from_model);
	// The true floorplan as a given one: placed on the reconstructed walls, then compared
	// where it lands (corners as sets: a symmetric room fits turned too).
	const FloorplanRegistration registration = register_floorplan(p_result.truth.floorplan, transform_samples(p_result.samples, p_result.world_from_model));
	double registration_error_m = -1.0;
	if (registration.ok) {
		Floorplan placed = p_result.truth.floorplan;
		for (Vec2 &p : placed.points) {
			const glm::dvec3 q = transform_point(registration.world_from_given, glm::dvec3(p.x, 0.0, p.y));
			p = { q.x, q.z };
		}
		registration_error_m = compare_rooms(placed, p_result.world_from_model, p_result.truth.floorplan, p_result.true_world_from_model).corner_error_max_m;
	}
	std::printf("registration of the true floorplan: %s\n", registration.message.c_str());
	std::printf("corner_error_max_m=%.4f ceiling_error_m=%.4f up_error_deg=%.3f registration_error_m=%.4f registration_rms_m=%.4f "
				"corner_error_fitted_m=%.4f\n",
			comparison.corner_error_max_m, comparison.ceiling_error_m, comparison.up_error_deg, registration_error_m, registration.residual_rms_m,
			comparison.corner_error_fitted_m);
}

int run(int argc, char **argv) {
	RoomArgs args;
	if (const std::optional<int> done = parse_arguments(argc, argv, &args)) {
		return *done;
	}
	if (const std::optional<int> refused = check_outputs(&args)) {
		return *refused;
	}
	if (!args.quiet) {
		args.options.progress = [](const std::string &p_line) { std::cerr << p_line << "\n"; };
	}
	const RoomSweepResult result = sweep_room(args.options);
	if (!result.error.empty()) {
		std::fprintf(stderr, "roomprobe_room: %s\n", result.error.c_str());
		return 1;
	}
	print_estimate(result);
	const int written = write_outputs(args, result);
	if (written != 0) {
		return written;
	}
	if (result.has_truth) {
		print_comparison(result);
	}
	return 0;
}

} // namespace

int main(int argc, char **argv) {
	return roomprobe::cli::guarded_main("roomprobe_room", [&] { return run(argc, argv); });
}
