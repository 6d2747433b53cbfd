#include "truth_scene.h"

#include <io/yaml_fields.h>
#include <io/input_path.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace roomprobe {

TruthSceneResult load_truth_scene(const std::string &p_recording) {
	TruthSceneResult result;
	const std::string path = (std::filesystem::path(p_recording) / "synth.yaml").string();
	result.error = input_file_problem(path, "missing (the true scene is known only for recordings made by ./roomprobe synth)");
	if (!result.error.empty()) {
		return result;
	}
	synth::SceneOptions options;
	std::string name;
	try {
		cv::FileStorage info;
		const std::string problem = open_yaml_file(path, &info);
		if (!problem.empty()) {
			result.error = problem;
			return result;
		}
		if (info["scene"].empty() || !info["scene"].isString()) {
			result.error = path + ": no `scene` (the synthetic scene's name)";
			return result;
		}
		name = std::string(info["scene"]);
		if (!info["duration_s"].empty()) {
			options.duration_s = double(info["duration_s"]);
		}
		if (info["scene_panorama"].empty() || !info["scene_panorama"].isString()) {
			// Recordings made before issue #16 do not say: the panorama (living_room's window,
			// panorama_room's walls) would be guessed wrong.
			if (name == "living_room" || name == "panorama_room") {
				result.error = path + ": no `scene_panorama` (made before it was recorded): make the recording again with ./roomprobe synth";
				return result;
			}
		} else if (std::string(info["scene_panorama"]) != "none") {
			options.panorama_path = std::string(info["scene_panorama"]);
		}
	} catch (const cv::Exception &e) {
		result.error = path + ": cannot be read (" + e.what() + ")";
		return result;
	}
	const synth::SceneResult scene = synth::make_scene(name, options);
	if (!scene.ok) {
		result.error = path + ": scene `" + name + "`: " + scene.error;
		return result;
	}
	result.renderer = std::make_unique<synth::SynthRenderer>(scene.scene);
	if (!result.renderer->ok()) {
		result.error = path + ": scene `" + name + "`: " + result.renderer->error();
		result.renderer.reset();
		return result;
	}
	result.ok = true;
	return result;
}

bool on_prism(const Floorplan &p_floorplan, const glm::dvec3 &p_point, double p_tolerance_m) {
	if (std::abs(p_point.y) <= p_tolerance_m || std::abs(p_point.y - p_floorplan.ceiling_height_m) <= p_tolerance_m) {
		return true;
	}
	const size_t n = p_floorplan.points.size();
	for (size_t i = 0; i < n; i++) {
		const glm::dvec2 a(p_floorplan.points[i].x, p_floorplan.points[i].y);
		const glm::dvec2 b(p_floorplan.points[(i + 1) % n].x, p_floorplan.points[(i + 1) % n].y);
		const glm::dvec2 p(p_point.x, p_point.z), ab = b - a;
		const double length_sq = glm::dot(ab, ab);
		const double t = length_sq > 0.0 ? std::clamp(glm::dot(p - a, ab) / length_sq, 0.0, 1.0) : 0.0;
		if (glm::length(p - (a + t * ab)) <= p_tolerance_m) {
			return true;
		}
	}
	return false;
}

namespace {

// One value per face pixel from the first hit along its direction, faces in parallel.
template <typename T, typename F>
std::array<cv::Mat, 6> per_direction(const synth::SynthRenderer &p_scene, const glm::dvec3 &p_position, int p_size, int p_type, F p_value) {
	std::array<cv::Mat, 6> faces;
	for (cv::Mat &face : faces) {
		face = cv::Mat(p_size, p_size, p_type, cv::Scalar(0));
	}
	tbb::parallel_for(0, 6 * p_size, [&](int p_row) {
		const int f = p_row / p_size, v = p_row % p_size;
		T *out = faces[size_t(f)].ptr<T>(v);
		for (int u = 0; u < p_size; u++) {
			const synth::Hit hit = p_scene.intersect(p_position, cubemap_direction(f, u, v, p_size));
			out[u] = hit.hit ? p_value(hit) : T(0);
		}
	});
	return faces;
}

} // namespace

std::array<cv::Mat, 6> prism_directions(const synth::SynthRenderer &p_scene, const Floorplan &p_floorplan, const glm::dvec3 &p_position, int p_size) {
	return per_direction<uint8_t>(p_scene, p_position, p_size, CV_8UC1,
			[&](const synth::Hit &p_hit) { return on_prism(p_floorplan, p_hit.point) ? uint8_t(255) : uint8_t(0); });
}

std::array<cv::Mat, 6> true_distances(const synth::SynthRenderer &p_scene, const glm::dvec3 &p_position, int p_size) {
	return per_direction<float>(p_scene, p_position, p_size, CV_32FC1, [](const synth::Hit &p_hit) { return float(p_hit.distance); });
}

} // namespace roomprobe
