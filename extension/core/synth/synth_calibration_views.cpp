// The checkerboard views of a synthetic recording (synth_sequence.h): the board as a scene, its
// fixed poses for each camera and for both at once, and the calibration and photometric views
// written into the recording's calibration/ folder. Split from synth_sequence.cpp to keep each
// file short.
#include <io/opencv.h>
#include <io/image_codec.h>

#include "synth_sequence.h"

#include <camera/omni_camera.h>
#include <camera/pinhole_camera.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

namespace roomprobe::synth {

namespace {

constexpr double PI = std::numbers::pi;

// A rotation whose z axis is p_z; p_x_hint gives the x axis (made orthogonal).
glm::dquat frame_rotation(const glm::dvec3 &p_z, const glm::dvec3 &p_x_hint) {
	const glm::dvec3 z = glm::normalize(p_z);
	glm::dvec3 x = p_x_hint - glm::dot(p_x_hint, z) * z;
	if (glm::length(x) < 1e-9) {
		x = std::abs(z.x) < 0.9 ? glm::dvec3(1.0, 0.0, 0.0) : glm::dvec3(0.0, 1.0, 0.0);
		x = x - glm::dot(x, z) * z;
	}
	x = glm::normalize(x);
	const glm::dvec3 y = glm::cross(z, x);
	return glm::normalize(glm::quat_cast(glm::dmat3(x, y, z)));
}

// A board posed with its centre at p_center and its z axis along p_z (x along p_x_hint).
Pose board_pose(const CheckerboardSpec &p_board, const glm::dvec3 &p_center, const glm::dvec3 &p_z, const glm::dvec3 &p_x_hint) {
	Pose pose;
	pose.rotation = frame_rotation(p_z, p_x_hint);
	const glm::dvec3 half(0.5 * p_board.squares_x * p_board.square_m, 0.5 * p_board.squares_y * p_board.square_m, 0.0);
	pose.translation = p_center - glm::mat3_cast(pose.rotation) * half;
	return pose;
}

std::string write_png_rgb(const std::string &p_path, const cv::Mat &p_rgb) {
	cv::Mat bgr;
	cv::cvtColor(p_rgb, bgr, cv::COLOR_RGB2BGR);
	return png_write(p_path, bgr);
}

void write_pose(cv::FileStorage &p_fs, const std::string &p_name, const Pose &p_pose) {
	p_fs << p_name << "{";
	p_fs << "rotation_xyzw" << "[:" << p_pose.rotation.x << p_pose.rotation.y << p_pose.rotation.z << p_pose.rotation.w << "]";
	p_fs << "translation_m" << "[:" << p_pose.translation.x << p_pose.translation.y << p_pose.translation.z << "]";
	p_fs << "}";
}

// One rendered image: the camera (rgb or fisheye), the board in that camera's frame, the file.
struct Shot {
	bool is_rgb;
	Pose camera_from_board;
	std::string image; // relative to p_folder
	std::string depth; // RGB of a pair: its depth image, else empty
	int pair; // -1: a view of one camera
};

// The views write_calibration_views renders: each camera's own boards, then (with a fisheye) the
// pairs both see at once.
std::vector<Shot> calibration_shots(const Rig &p_rig, const CheckerboardSpec &p_board) {
	std::vector<Shot> shots;
	char name[64];
	for (int camera = 0; camera < 2; ++camera) {
		const bool is_rgb = camera == 0;
		const std::vector<Pose> poses = is_rgb ? pinhole_board_poses(p_board) : fisheye_board_poses(p_board);
		for (size_t v = 0; v < poses.size(); ++v) {
			std::snprintf(name, sizeof(name), "calibration/%s/%03zu.png", is_rgb ? "rgb" : "fisheye", v);
			shots.push_back({ is_rgb, poses[v], name, "", -1 });
		}
	}
	if (p_rig.has_fisheye()) {
		const std::vector<Pose> pairs = pair_board_poses(p_board);
		const Pose fisheye_from_rgb = inverse(p_rig.rgb_from_fisheye);
		for (size_t v = 0; v < pairs.size(); ++v) {
			std::snprintf(name, sizeof(name), "calibration/pairs/%03zu_rgb.png", v);
			char depth[64];
			std::snprintf(depth, sizeof(depth), "calibration/pairs/%03zu_depth.png", v);
			shots.push_back({ true, pairs[v], name, depth, int(v) });
			std::snprintf(name, sizeof(name), "calibration/pairs/%03zu_fisheye.png", v);
			shots.push_back({ false, compose(fisheye_from_rgb, pairs[v]), name, "", int(v) });
		}
	}
	return shots;
}

} // namespace

// ---------------------------------------------------------------- checkerboards

std::vector<glm::dvec3> checkerboard_corners(const CheckerboardSpec &p_board) {
	std::vector<glm::dvec3> corners;
	for (int j = 0; j + 1 < p_board.squares_y; ++j) {
		for (int i = 0; i + 1 < p_board.squares_x; ++i) {
			corners.emplace_back((i + 1) * p_board.square_m, (j + 1) * p_board.square_m, 0.0);
		}
	}
	return corners;
}

Scene make_checkerboard_scene(const CheckerboardSpec &p_board, const Pose &p_camera_from_board) {
	Scene scene;
	scene.name = "checkerboard";
	Material squares;
	squares.name = "checkerboard";
	squares.albedo.pattern = Pattern::Checker;
	squares.albedo.a = Color(0.03f); // the first square is black
	squares.albedo.b = Color(0.85f);
	squares.albedo.scale_m = p_board.square_m;
	squares.unlit = true;
	Material margin;
	margin.name = "checkerboard_margin";
	margin.albedo.a = Color(0.85f);
	margin.unlit = true;
	const int squares_material = add_material(&scene, squares);
	const int margin_material = add_material(&scene, margin);
	const glm::dmat3 r = glm::mat3_cast(p_camera_from_board.rotation);
	const glm::dvec3 t = p_camera_from_board.translation;
	const double w = p_board.squares_x * p_board.square_m, h = p_board.squares_y * p_board.square_m;
	Quad board;
	board.corner = t;
	board.edge_u = r * glm::dvec3(w, 0.0, 0.0);
	board.edge_v = r * glm::dvec3(0.0, h, 0.0);
	board.material = squares_material;
	scene.quads.push_back(board);
	// The white margin, 1 mm behind the squares.
	Quad back;
	back.corner = t + r * glm::dvec3(-p_board.margin_m, -p_board.margin_m, 0.001);
	back.edge_u = r * glm::dvec3(w + 2.0 * p_board.margin_m, 0.0, 0.0);
	back.edge_v = r * glm::dvec3(0.0, h + 2.0 * p_board.margin_m, 0.0);
	back.material = margin_material;
	scene.quads.push_back(back);
	scene.background = Color(0.25f);
	return scene;
}

std::vector<Pose> pinhole_board_poses(const CheckerboardSpec &p_board) {
	// Centre, distance and tilt (degrees about the board's x and y) of each view.
	struct View {
		double x, y, z, tilt_x_deg, tilt_y_deg, spin_deg;
	};
	const View views[] = {
		{ 0.0, 0.0, 0.6, 0.0, 0.0, 0.0 },
		{ -0.12, -0.08, 0.55, 25.0, -20.0, 5.0 },
		{ 0.12, 0.08, 0.65, -25.0, 20.0, -5.0 },
		{ 0.14, -0.1, 0.7, 15.0, 30.0, 10.0 },
		{ -0.15, 0.1, 0.75, -20.0, -30.0, -10.0 },
		{ 0.0, 0.0, 0.9, 35.0, 0.0, 0.0 },
		{ 0.05, -0.02, 0.5, 0.0, 35.0, 20.0 },
		{ -0.05, 0.05, 0.8, -35.0, 10.0, -15.0 },
	};
	std::vector<Pose> poses;
	for (const View &v : views) {
		const double ax = v.tilt_x_deg * PI / 180.0, ay = v.tilt_y_deg * PI / 180.0, az = v.spin_deg * PI / 180.0;
		// The board's normal (z) points away from the camera, tilted; x mostly along the camera's x.
		const glm::dvec3 z = glm::normalize(glm::dvec3(std::sin(ay), -std::sin(ax), std::cos(ax) * std::cos(ay)));
		const glm::dvec3 x_hint(std::cos(az), std::sin(az), 0.0);
		poses.push_back(board_pose(p_board, { v.x, v.y, v.z }, z, x_hint));
	}
	return poses;
}

std::vector<Pose> fisheye_board_poses(const CheckerboardSpec &p_board) {
	// Off-axis angle and azimuth of the board's centre, distance, and extra tilt.
	struct View {
		double theta_deg, phi_deg, distance_m, tilt_deg;
	};
	const View views[] = {
		{ 0.0, 0.0, 0.35, 0.0 },
		{ 30.0, 0.0, 0.35, 10.0 },
		{ 35.0, 120.0, 0.4, -10.0 },
		{ 40.0, 240.0, 0.35, 15.0 },
		{ 55.0, 60.0, 0.4, 0.0 },
		{ 60.0, 180.0, 0.4, 10.0 },
		{ 65.0, 300.0, 0.45, -10.0 },
		{ 20.0, 270.0, 0.3, 20.0 },
	};
	std::vector<Pose> poses;
	for (const View &v : views) {
		const double theta = v.theta_deg * PI / 180.0, phi = v.phi_deg * PI / 180.0, tilt = v.tilt_deg * PI / 180.0;
		const glm::dvec3 direction(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
		// Facing the camera (normal along the line of sight), tilted about the board's x.
		const glm::dvec3 across = glm::normalize(glm::cross(direction, glm::dvec3(0.0, 0.0, 1.0)) + glm::dvec3(1e-9, 0.0, 0.0));
		const glm::dvec3 up = glm::cross(direction, across);
		const glm::dvec3 z = glm::normalize(std::cos(tilt) * direction + std::sin(tilt) * up);
		poses.push_back(board_pose(p_board, direction * v.distance_m, z, across));
	}
	return poses;
}

std::vector<Pose> pair_board_poses(const CheckerboardSpec &p_board) {
	// In the RGB camera's frame: the board ahead of it and raised, where the upward fisheye sees it
	// near its horizon (about 75 to 90 degrees off its axis) while it is inside the RGB image. Centre
	// (x, elevation in degrees, distance), then tilt about the board's x and y, and spin.
	struct View {
		double x, elevation_deg, distance_m, tilt_x_deg, tilt_y_deg, spin_deg;
	};
	const View views[] = {
		{ 0.0, 13.0, 0.9, 0.0, 0.0, 0.0 },
		{ -0.16, 12.0, 0.85, 10.0, -20.0, 5.0 },
		{ 0.16, 14.0, 0.95, -10.0, 20.0, -5.0 },
		{ 0.08, 15.0, 1.05, 20.0, 10.0, 10.0 },
		{ -0.08, 12.5, 1.0, -15.0, -10.0, -10.0 },
		{ 0.0, 14.0, 1.15, 25.0, 0.0, 3.0 },
	};
	std::vector<Pose> poses;
	for (const View &v : views) {
		const double elevation = v.elevation_deg * PI / 180.0;
		const glm::dvec3 centre(v.x, -std::sin(elevation) * v.distance_m, std::cos(elevation) * v.distance_m);
		const double ax = v.tilt_x_deg * PI / 180.0, ay = v.tilt_y_deg * PI / 180.0, az = v.spin_deg * PI / 180.0;
		// The board's normal points away from the cameras, along the line of sight, tilted.
		const glm::dvec3 sight = glm::normalize(centre);
		const glm::dvec3 across = glm::normalize(glm::cross(glm::dvec3(0.0, 1.0, 0.0), sight)); // the image's x
		const glm::dvec3 up = glm::cross(sight, across);
		const glm::dvec3 z = glm::normalize(std::cos(ax) * std::cos(ay) * sight + std::sin(ax) * up + std::sin(ay) * across);
		const glm::dvec3 x_hint = std::cos(az) * across + std::sin(az) * up;
		poses.push_back(board_pose(p_board, centre, z, x_hint));
	}
	return poses;
}

CalibrationResult write_photometric_views(const std::string &p_folder, const SynthRenderer &p_renderer, const OmniParams &p_fisheye,
		const Pose &p_world_from_fisheye, const FisheyeOptions &p_options) {
	CalibrationResult result;
	namespace fs = std::filesystem;
	const fs::path root = fs::path(p_folder) / "calibration";
	std::error_code ec;
	fs::create_directories(root / "exposure", ec);
	if (ec) {
		result.error = (root / "exposure").string() + ": cannot create the folder (" + ec.message() + ")";
		return result;
	}
	const std::string yaml_path = (root / "photometric.yaml").string();
	cv::FileStorage out;
	try {
		if (!out.open(yaml_path, cv::FileStorage::WRITE)) {
			result.error = yaml_path + ": cannot write";
			return result;
		}
	} catch (const cv::Exception &e) {
		result.error = yaml_path + ": cannot write (" + e.what() + ")";
		return result;
	}
	out << "roomprobe_photometric_views" << 1;
	out << "reference_exposure_us" << SYNTH_EXPOSURE_UNIT_US * p_options.exposure;
	// One rendering of the scene's radiance (exposure 1, vignetted), encoded at each stop.
	FisheyeOptions unit = p_options;
	unit.exposure = 1.0;
	const FisheyeImage scene = render_fisheye(p_renderer, p_fisheye, p_world_from_fisheye, 0.0, unit);
	out << "exposure_sweep" << "[";
	char name[64];
	for (int half_stop = -8; half_stop <= 8; half_stop++) {
		const double exposure = p_options.exposure * std::pow(2.0, 0.5 * half_stop);
		std::snprintf(name, sizeof(name), "exposure/%03d.png", half_stop + 8);
		const std::string error = write_png_rgb((root / name).string(), encode_8bit(scene.radiance * exposure, p_options.tone_curve, p_options.channel_gains));
		if (!error.empty()) {
			result.error = error;
			return result;
		}
		out << "{" << "image" << name << "exposure_us" << SYNTH_EXPOSURE_UNIT_US * exposure << "}";
		++result.views;
	}
	out << "]";
	// The flat field: radiance 0.7 / exposure everywhere, so the centre sits high in the range.
	cv::Mat flat(p_fisheye.height, p_fisheye.width, CV_32FC3, cv::Scalar::all(0));
	for (int y = 0; y < flat.rows; y++) {
		cv::Vec3f *row = flat.ptr<cv::Vec3f>(y);
		for (int x = 0; x < flat.cols; x++) {
			const glm::dvec2 pixel(x, y);
			if (omni_pixel_valid(p_fisheye, pixel)) {
				row[x] = cv::Vec3f::all(float(0.7 * fisheye_vignetting(p_fisheye, pixel, p_options.vignetting_edge_gain)));
			}
		}
	}
	const std::string error = write_png_rgb((root / "flat_field.png").string(), encode_8bit(flat, p_options.tone_curve, p_options.channel_gains));
	if (!error.empty()) {
		result.error = error;
		return result;
	}
	out << "flat_field" << "{" << "image" << "flat_field.png" << "exposure_us" << SYNTH_EXPOSURE_UNIT_US * p_options.exposure << "}";
	++result.views;
	out.release();
	result.ok = true;
	return result;
}

CalibrationResult write_calibration_views(const std::string &p_folder, const Rig &p_rig, const CheckerboardSpec &p_board, int p_samples_per_axis,
		const FisheyeOptions &p_fisheye, const std::function<void(const std::string &)> &p_progress) {
	CalibrationResult result;
	namespace fs = std::filesystem;
	const fs::path root = fs::path(p_folder) / "calibration";
	std::error_code ec;
	for (const char *sub : { "rgb", "fisheye", "pairs" }) {
		fs::create_directories(root / sub, ec);
		if (ec) {
			result.error = (root / sub).string() + ": cannot create the folder (" + ec.message() + ")";
			return result;
		}
	}
	const std::string yaml_path = (root / "boards.yaml").string();
	cv::FileStorage fs_out;
	try {
		if (!fs_out.open(yaml_path, cv::FileStorage::WRITE)) {
			result.error = yaml_path + ": cannot write";
			return result;
		}
	} catch (const cv::Exception &e) {
		result.error = yaml_path + ": cannot write (" + e.what() + ")";
		return result;
	}
	fs_out << "roomprobe_calibration_views" << 1;
	fs_out << "board" << "{";
	fs_out << "squares_x" << p_board.squares_x << "squares_y" << p_board.squares_y;
	fs_out << "inner_corners_x" << p_board.squares_x - 1 << "inner_corners_y" << p_board.squares_y - 1;
	fs_out << "square_m" << p_board.square_m << "margin_m" << p_board.margin_m;
	fs_out << "frame" << "origin at the outer top-left corner of the squares (the first square is black); x along squares_x, y along squares_y, z away from the printed face; inner corner (i, j) at ((i + 1) square_m, (j + 1) square_m, 0), i fastest";
	fs_out << "}";
	fs_out << "views" << "[";
	const std::vector<glm::dvec3> corners = checkerboard_corners(p_board);
	const std::vector<Shot> shots = calibration_shots(p_rig, p_board);
	size_t done = 0;
	for (const Shot &shot : shots) {
		if (p_progress && (done * 10 / shots.size() != (done + 1) * 10 / shots.size() || done == 0)) {
			p_progress("calibration views: " + std::to_string(done) + " of " + std::to_string(shots.size()) + " rendered");
		}
		++done;
		const Scene scene = make_checkerboard_scene(p_board, shot.camera_from_board);
		const SynthRenderer renderer(scene);
		if (!renderer.ok()) {
			result.error = "checkerboard scene: " + renderer.error();
			return result;
		}
		cv::Mat image, depth;
		if (shot.is_rgb) {
			RgbdOptions options;
			options.samples_per_axis = p_samples_per_axis;
			options.noise_seed = uint64_t(result.views + 1);
			RgbdImage rendered = render_rgbd(renderer, p_rig.rgb, p_rig.depth_scale_m, Pose(), 0.0, options);
			image = rendered.rgb;
			depth = rendered.depth;
		} else {
			FisheyeOptions options = p_fisheye;
			options.samples_per_axis = p_samples_per_axis;
			image = render_fisheye(renderer, p_rig.fisheye, Pose(), 0.0, options).image;
		}
		std::string error = write_png_rgb((fs::path(p_folder) / shot.image).string(), image);
		if (error.empty() && !shot.depth.empty()) {
			const std::string path = (fs::path(p_folder) / shot.depth).string();
			error = png_write(path, depth);
		}
		if (!error.empty()) {
			result.error = error;
			return result;
		}
		fs_out << "{";
		fs_out << "camera" << (shot.is_rgb ? "rgb" : "fisheye");
		fs_out << "image" << shot.image;
		if (shot.pair >= 0) {
			fs_out << "pair" << shot.pair;
		}
		if (!shot.depth.empty()) {
			fs_out << "depth" << shot.depth;
		}
		write_pose(fs_out, "camera_from_board", shot.camera_from_board);
		// The true pixel of every inner corner; -1, -1 where the model cannot see it.
		fs_out << "corners_px" << "[:";
		for (const glm::dvec3 &corner : corners) {
			const glm::dvec3 p = transform_point(shot.camera_from_board, corner);
			glm::dvec2 pixel(-1.0);
			const bool seen = shot.is_rgb ? project_pinhole(p_rig.rgb, p, &pixel) : project_omni(p_rig.fisheye, p, &pixel);
			if (!seen) {
				pixel = glm::dvec2(-1.0);
			}
			fs_out << pixel.x << pixel.y;
		}
		fs_out << "]";
		fs_out << "}";
		++result.views;
	}
	fs_out << "]";
	fs_out.release();
	result.ok = true;
	return result;
}

} // namespace roomprobe::synth
