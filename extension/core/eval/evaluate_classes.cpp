// The per-class scoring of evaluate_recording's maps (evaluate_internal.h): the maps at the scored
// size, the live map split by direction and by geometry, the two models' oracles and the mirror
// spheres.

#include "evaluate_internal.h"
#include "truth_scene.h"

#include <engine/live_room.h>
#include <envmap/coarse_render.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace roomprobe::evaluate_detail {

Cubemap to_cubemap(const CubemapFaces &p_faces, int p_size) {
	Cubemap map;
	map.size = p_size;
	for (int f = 0; f < 6; f++) {
		if (p_faces[f].cols == p_size) {
			map.faces[f] = p_faces[f];
		} else {
			cv::resize(p_faces[f], map.faces[f], cv::Size(p_size, p_size), 0, 0, p_faces[f].cols > p_size ? cv::INTER_AREA : cv::INTER_LINEAR);
		}
	}
	return map;
}

Cubemap to_cubemap(const Cubemap &p_map, int p_size) {
	Cubemap map = to_cubemap(p_map.faces, p_size);
	if (has_distances(p_map)) {
		for (int f = 0; f < 6; f++) {
			if (p_map.size == p_size) {
				map.distance_m[size_t(f)] = p_map.distance_m[size_t(f)];
			} else {
				cv::resize(p_map.distance_m[size_t(f)], map.distance_m[size_t(f)], cv::Size(p_size, p_size), 0, 0, cv::INTER_NEAREST);
			}
		}
	}
	return map;
}

namespace {

// The tone-mapped PSNR of p_estimate over each class of pixels that p_class(face, y, x) returns
// (0 .. p_count - 1), and each class's share of the map.
template <typename ClassOf>
void score_classes(const Cubemap &p_estimate, const Cubemap &p_truth, int p_count, DirectionClassScores *r_scores, ClassOf p_class) {
	std::vector<double> squared(size_t(p_count), 0.0), pixels(size_t(p_count), 0.0);
	const int size = p_truth.size;
	for (int f = 0; f < 6; f++) {
		const cv::Mat estimate = tone_map_face(p_estimate.faces[f]), truth = tone_map_face(p_truth.faces[f]);
		for (int y = 0; y < size; y++) {
			for (int x = 0; x < size; x++) {
				const size_t c = size_t(p_class(f, y, x));
				const cv::Vec3b e = estimate.at<cv::Vec3b>(y, x), t = truth.at<cv::Vec3b>(y, x);
				for (int k = 0; k < 3; k++) {
					squared[c] += (double(e[k]) - t[k]) * (double(e[k]) - t[k]);
				}
				pixels[c] += 1.0;
			}
		}
	}
	const double total = 6.0 * size * size;
	for (size_t c = 0; c < size_t(p_count); c++) {
		r_scores[c].share = pixels[c] / total;
		const double mse = pixels[c] > 0.0 ? squared[c] / (3.0 * pixels[c]) : 0.0;
		r_scores[c].psnr_db = pixels[c] == 0.0 ? 0.0 : (mse > 0.0 ? std::min(PSNR_CAP_DB, 10.0 * std::log10(255.0 * 255.0 / mse)) : PSNR_CAP_DB);
	}
}

} // namespace

FaceMasks dense_coverage(const Cubemap &p_live, const Cubemap &p_coarse_only) {
	FaceMasks covered;
	for (int f = 0; f < 6; f++) {
		cv::Mat difference, channels[3];
		cv::absdiff(p_live.faces[size_t(f)], p_coarse_only.faces[size_t(f)], difference);
		cv::split(difference, channels);
		covered[size_t(f)] = (channels[0] + channels[1] + channels[2]) > 0.0f; // any channel differs
	}
	return covered;
}

void split_by_direction(const LiveRoom &p_engine, const CoarseCubemapRenderer &p_renderer, const Cubemap &p_with_dense, const FaceMasks &p_dense,
		const Cubemap &p_truth, const glm::dvec3 &p_probe, int p_render_size, DirectionClassScores r_scores[DIRECTION_CLASS_COUNT]) {
	const CoarseTexture &texture = p_engine.coarse_model()->texture();
	cv::Mat masks(texture.color.size(), CV_32FC3, cv::Scalar::all(0.0));
	for (int y = 0; y < masks.rows; y++) {
		const float *fisheye_quality = texture.quality.ptr<float>(y); // > 0: a fisheye observation (an RGB one has 0)
		const uint8_t *saturated = texture.saturated.empty() ? nullptr : texture.saturated.ptr<uint8_t>(y);
		cv::Vec3f *out = masks.ptr<cv::Vec3f>(y);
		for (int x = 0; x < masks.cols; x++) {
			const bool rgb = !texture.rgb_quality.empty() && texture.rgb_quality.at<float>(y, x) > 0.0f;
			out[x] = cv::Vec3f(fisheye_quality[x] > 0.0f ? 1.0f : 0.0f, saturated && saturated[x] ? 1.0f : 0.0f, rgb ? 1.0f : 0.0f);
		}
	}
	const int size = p_truth.size;
	const Pose room_from_world = inverse(p_engine.config().world_from_room); // the coarse model's frame
	const Cubemap seen = to_cubemap(p_renderer.render(masks, transform_point(room_from_world, p_probe), p_render_size, room_from_world.rotation).faces, size);
	score_classes(p_with_dense, p_truth, DIRECTION_CLASS_COUNT, r_scores, [&](int p_face, int p_y, int p_x) {
		const cv::Vec3f mask = seen.faces[p_face].at<cv::Vec3f>(p_y, p_x);
		if (mask[0] > 0.5f) {
			return mask[1] > 0.5f ? int(DIRECTIONS_SATURATED) : int(DIRECTIONS_FISHEYE);
		}
		const bool dense = p_dense[size_t(p_face)].at<uint8_t>(p_y, p_x) != 0;
		return dense || mask[2] > 0.5f ? int(DIRECTIONS_RGBD_ONLY) : int(DIRECTIONS_NEVER_SEEN);
	});
}

void split_by_geometry(const Cubemap &p_with_dense, const FaceMasks &p_dense, const Cubemap &p_truth, const FaceMasks &p_prism,
		DirectionClassScores r_scores[GEOMETRY_CLASS_COUNT]) {
	score_classes(p_with_dense, p_truth, GEOMETRY_CLASS_COUNT, r_scores, [&](int p_face, int p_y, int p_x) {
		const bool dense = p_dense[size_t(p_face)].at<uint8_t>(p_y, p_x) != 0;
		if (p_prism[size_t(p_face)].at<uint8_t>(p_y, p_x)) {
			return dense ? int(GEOMETRY_PRISM_DENSE) : int(GEOMETRY_PRISM_COARSE);
		}
		return dense ? int(GEOMETRY_CONTENTS_DENSE) : int(GEOMETRY_CONTENTS_COARSE);
	});
}

void compose_oracles(const Cubemap &p_live, const FaceMasks &p_dense, const Cubemap &p_truth, const FaceMasks &p_prism, Cubemap *r_coarse_oracle,
		Cubemap *r_dense_oracle) {
	*r_coarse_oracle = clone_cubemap(p_live);
	*r_dense_oracle = clone_cubemap(p_live);
	for (int f = 0; f < 6; f++) {
		for (int y = 0; y < p_truth.size; y++) {
			const uint8_t *prism = p_prism[size_t(f)].ptr<uint8_t>(y);
			const uint8_t *dense = p_dense[size_t(f)].ptr<uint8_t>(y);
			const cv::Vec3f *truth = p_truth.faces[f].ptr<cv::Vec3f>(y);
			cv::Vec3f *coarse_oracle = r_coarse_oracle->faces[f].ptr<cv::Vec3f>(y);
			cv::Vec3f *dense_oracle = r_dense_oracle->faces[f].ptr<cv::Vec3f>(y);
			for (int x = 0; x < p_truth.size; x++) {
				if (prism[x] && !dense[x]) {
					coarse_oracle[x] = truth[x];
				}
				if (!prism[x]) {
					dense_oracle[x] = truth[x];
				}
			}
		}
	}
}

void measure_mirrors(const synth::SynthRenderer &p_scene, const Cubemap &p_truth, const Cubemap &p_live, const glm::dvec3 &p_probe, double p_time_s,
		EvaluationResult *r_result) {
	Cubemap true_map = p_truth;
	true_map.distance_m = true_distances(p_scene, p_probe, p_truth.size);
	r_result->mirrors.clear();
	r_result->mirror_clearance_m = std::numeric_limits<double>::infinity();
	for (const cv::Mat &face : true_map.distance_m) {
		double lowest = std::numeric_limits<double>::infinity();
		cv::minMaxLoc(face, &lowest, nullptr, nullptr, nullptr, face > 0.0f); // rays that hit nothing do not count
		r_result->mirror_clearance_m = std::min(r_result->mirror_clearance_m, lowest);
	}
	for (const double radius : MIRROR_RADII_M) {
		if (radius > 0.95 * r_result->mirror_clearance_m) {
			continue; // the sphere would reach into the scene
		}
		for (const bool true_one : { true, false }) {
			r_result->mirrors.push_back({ radius, true_one, mirror_sphere_error(p_scene, true_one ? true_map : p_live, p_probe, radius, p_time_s) });
		}
	}
}

} // namespace roomprobe::evaluate_detail
