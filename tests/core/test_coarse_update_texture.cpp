// Updating the coarse model's texture from fisheye frames (paper §4.3): unit checks on the
// sampling and the policies, and, on a synthetic two-rooms sequence, the "keep the best
// observation" policy against the paper's "last observation" one, each texel against the scene's
// true radiance at the texel.

#include "io/opencv.h"
#include "camera/omni_camera.h"
#include "coarse/coarse_texture.h"
#include "coarse/occlusion.h"
#include "coarse/texture_update.h"
#include "math/pose.h"
#include "rig/rig.h"
#include "room/reference_rooms.h"
#include "room/room_mesh.h"
#include "synth/synth_renderer.h"
#include "synth/synth_scene.h"
#include "synth/synth_sequence.h"
#include "synth_test_rig.h"

#include <doctest/doctest.h>
#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

using namespace roomprobe;

namespace {

RoomMesh build(const Floorplan &p_floorplan) {
	const RoomMeshResult result = build_room_mesh(p_floorplan);
	REQUIRE_MESSAGE(result.ok, result.error);
	return result.mesh;
}

// A fisheye at p_position looking along world +Y (up), its image y along world +Z.
Pose upward_fisheye(const glm::dvec3 &p_position) {
	// Columns: camera x -> world +X, camera y -> world +Z... choose a right-handed frame:
	// x_c = +X, z_c = +Y, y_c = z_c x x_c = +Y x +X = -Z.
	const glm::dmat3 world_from_camera(glm::dvec3(1, 0, 0), glm::dvec3(0, 0, -1), glm::dvec3(0, 1, 0));
	Pose pose;
	pose.rotation = glm::quat_cast(world_from_camera);
	pose.translation = p_position;
	return pose;
}

} // namespace

TEST_CASE("coarse update: texel geometry, conversions, masks and the two policies") {
	const RoomMesh mesh = build(living_room());
	const TexelGeometry geometry = make_texel_geometry(mesh);
	REQUIRE(geometry.width == mesh.atlas_width);
	REQUIRE(geometry.surface_texels > 0);
	// 5 x 4 x 2.5 m: 2 * 20 m^2 + 18 * 2.5 m^2 = 85 m^2 of 0.0004 m^2 texels.
	CHECK(double(geometry.surface_texels) == doctest::Approx(85.0 / 0.0004).epsilon(0.01));

	const OmniParams params = test_rig().fisheye;
	const Pose centre = upward_fisheye(glm::dvec3(2.5, 1.2, 2.0));
	CoarseTexture texture = make_coarse_texture(mesh);
	CHECK(cv::countNonZero(texture.observed) == 0);

	// 8-bit RGB: value / 255; the ceiling (straight above) is seen, the floor (behind) is not.
	cv::Mat grey(params.height, params.width, CV_8UC3, cv::Scalar(51, 102, 255));
	TextureUpdateStats stats = update_coarse_texture(mesh, geometry, params, centre, grey, nullptr, &texture);
	CHECK(stats.texels_updated > 0);
	CHECK(stats.texels_updated == stats.texels_visible); // nothing observed before
	const Chart &ceiling = mesh.charts[mesh.floorplan.points.size() + 1];
	const Chart &floor = mesh.charts[mesh.floorplan.points.size()];
	const cv::Point above(ceiling.x + ceiling.w / 2, ceiling.y + ceiling.h / 2), below(floor.x + floor.w / 2, floor.y + floor.h / 2);
	CHECK(texture.observed.at<uint8_t>(above) == 255);
	CHECK(texture.updated.at<uint8_t>(above) == 255);
	CHECK(texture.color.at<cv::Vec3f>(above)[0] == doctest::Approx(0.2));
	CHECK(texture.color.at<cv::Vec3f>(above)[1] == doctest::Approx(0.4));
	CHECK(texture.color.at<cv::Vec3f>(above)[2] == doctest::Approx(1.0));
	CHECK(texture.quality.at<float>(above) > 0.0f);
	CHECK(texture.observed.at<uint8_t>(below) == 0);

	// A worse view (from a corner, further and more oblique) does not replace the best one...
	const Pose corner = upward_fisheye(glm::dvec3(0.4, 0.3, 0.4));
	cv::Mat grey1(params.height, params.width, CV_8UC1, cv::Scalar(10));
	CoarseTexture last { texture.color.clone(), texture.observed.clone(), texture.quality.clone(), texture.updated.clone(), texture.saturated.clone(), texture.rgb_quality.clone() };
	stats = update_coarse_texture(mesh, geometry, params, corner, grey1, nullptr, &texture);
	CHECK(stats.texels_visible > stats.texels_updated);
	CHECK(texture.updated.at<uint8_t>(above) == 0);
	CHECK(texture.color.at<cv::Vec3f>(above)[0] == doctest::Approx(0.2));
	// ... but does with the "last observation" policy.
	TextureUpdateOptions last_options;
	last_options.policy = TextureUpdatePolicy::Last;
	stats = update_coarse_texture(mesh, geometry, params, corner, grey1, nullptr, &last, last_options);
	CHECK(stats.texels_visible == stats.texels_updated);
	CHECK(last.updated.at<uint8_t>(above) == 255);
	CHECK(last.color.at<cv::Vec3f>(above)[0] == doctest::Approx(10.0 / 255.0));

	// The same view again replaces (the texture follows the scene), a float frame as is.
	cv::Mat bright(params.height, params.width, CV_32FC3, cv::Scalar(3.0, 2.0, 1.0));
	stats = update_coarse_texture(mesh, geometry, params, centre, bright, nullptr, &texture);
	CHECK(texture.updated.at<uint8_t>(above) == 255);
	CHECK(texture.color.at<cv::Vec3f>(above)[0] == doctest::Approx(3.0));

	// The visibility mask: masked texels are left alone.
	cv::Mat mask(mesh.atlas_height, mesh.atlas_width, CV_8UC1, cv::Scalar(255));
	mask.at<uint8_t>(above) = 0;
	stats = update_coarse_texture(mesh, geometry, params, centre, grey, &mask, &texture);
	CHECK(texture.updated.at<uint8_t>(above) == 0);
	CHECK(texture.color.at<cv::Vec3f>(above)[0] == doctest::Approx(3.0));

	// The convenience overload gives the same result.
	CoarseTexture a = make_coarse_texture(mesh), b = make_coarse_texture(mesh);
	update_coarse_texture(mesh, geometry, params, centre, grey, nullptr, &a);
	update_coarse_texture(mesh, params, centre, grey, nullptr, &b);
	CHECK(cv::norm(a.color, b.color, cv::NORM_INF) == 0.0);

	// Wrong inputs: nothing happens.
	cv::Mat wrong(10, 10, CV_16UC1, cv::Scalar(0));
	CHECK(update_coarse_texture(mesh, geometry, params, centre, wrong, nullptr, &a).texels_visible == 0);
	cv::Mat small_mask(3, 3, CV_8UC1, cv::Scalar(255));
	CHECK(update_coarse_texture(mesh, geometry, params, centre, grey, &small_mask, &a).texels_visible == 0);
}

TEST_CASE("coarse update: keeping the best observation is closer to the truth than keeping the last (two rooms)") {
	using namespace roomprobe::synth;
	SceneOptions scene_options;
	scene_options.duration_s = 10.0;
	const SceneResult scene = make_scene("two_rooms", scene_options);
	REQUIRE_MESSAGE(scene.ok, scene.error);
	SynthRenderer renderer(scene.scene);
	REQUIRE(renderer.ok());
	const Rig rig = test_rig();
	const HandheldTrajectory trajectory = make_handheld_trajectory(scene.scene, 3);
	const RoomMesh mesh = build(scene.scene.room.floorplan);
	const TexelGeometry geometry = make_texel_geometry(mesh);

	TextureUpdateOptions best_options, last_options;
	last_options.policy = TextureUpdatePolicy::Last;
	CoarseTexture best = make_coarse_texture(mesh), last = make_coarse_texture(mesh);
	FisheyeOptions fisheye_options;
	fisheye_options.vignetting_edge_gain = 1.0; // no vignetting: compare radiance directly
	const int frames = 20;
	double update_s = 0.0, mask_s = 0.0, render_s = 0.0;
	for (int k = 0; k < frames; ++k) {
		const double t = 0.5 * k;
		const Pose world_from_fisheye = compose(trajectory.world_from_rgb(t), rig.rgb_from_fisheye);
		auto start = std::chrono::steady_clock::now();
		const FisheyeImage frame = render_fisheye(renderer, rig.fisheye, world_from_fisheye, t, fisheye_options);
		render_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
		start = std::chrono::steady_clock::now();
		const cv::Mat mask = occlusion_mask(mesh, geometry, world_from_fisheye.translation);
		mask_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
		const TextureUpdateStats b = update_coarse_texture(mesh, geometry, rig.fisheye, world_from_fisheye, frame.radiance, &mask, &best, best_options);
		const TextureUpdateStats l = update_coarse_texture(mesh, geometry, rig.fisheye, world_from_fisheye, frame.radiance, &mask, &last, last_options);
		update_s += b.seconds;
		CHECK(l.texels_updated == l.texels_visible);
		CHECK(b.texels_updated <= l.texels_updated);
	}

	// The truth: the scene's radiance at each texel's surface point, seen from just inside the room
	// (Lambertian surfaces: the same from every direction). Texels hidden by furniture standing
	// against the wall are skipped.
	double error_best = 0.0, error_last = 0.0, differ_best = 0.0, differ_last = 0.0;
	size_t compared = 0, differing = 0;
	for (int y = 0; y < geometry.height; ++y) {
		for (int x = 0; x < geometry.width; ++x) {
			const size_t i = size_t(y) * geometry.width + x;
			if (geometry.charts[i] < 0 || !best.observed.at<uint8_t>(y, x) || !last.observed.at<uint8_t>(y, x)) {
				continue;
			}
			const double offset = 0.005;
			Hit hit;
			const Color truth = renderer.radiance(geometry.points[i] + offset * geometry.normals[i], -geometry.normals[i], 0.0, &hit);
			if (!hit.hit || std::abs(hit.distance - offset) > 1e-3) {
				continue;
			}
			const cv::Vec3f &cb = best.color.at<cv::Vec3f>(y, x), &cl = last.color.at<cv::Vec3f>(y, x);
			const float tr[3] = { truth.r, truth.g, truth.b };
			double eb = 0.0, el = 0.0;
			for (int c = 0; c < 3; ++c) {
				eb += std::abs(cb[c] - tr[c]);
				el += std::abs(cl[c] - tr[c]);
			}
			error_best += eb;
			error_last += el;
			++compared;
			if (cb != cl) {
				differ_best += eb;
				differ_last += el;
				++differing;
			}
		}
	}
	REQUIRE(compared > geometry.surface_texels / 4);
	const double mae_best = error_best / (3.0 * compared), mae_last = error_last / (3.0 * compared);
	MESSAGE("two_rooms, " << frames << " fisheye frames (1024 px), texel 0.02 m: " << compared << " texels observed of "
						  << geometry.surface_texels << "; MAE (linear radiance) best " << mae_best << ", last " << mae_last
						  << "; on the " << differing << " texels where they differ: best " << differ_best / (3.0 * std::max<size_t>(differing, 1))
						  << ", last " << differ_last / (3.0 * std::max<size_t>(differing, 1))
						  << "; per frame: update " << 1000.0 * update_s / frames << " ms, occlusion mask " << 1000.0 * mask_s / frames
						  << " ms (render " << 1000.0 * render_s / frames << " ms)");
	CHECK(mae_best <= mae_last);
}

TEST_CASE("coarse update: the lighting estimate's sparse samples are the 'last' policy's update on its grid") {
	const RoomMesh mesh = build(living_room());
	const TexelGeometry geometry = make_texel_geometry(mesh);
	const OmniParams params = test_rig().fisheye;
	const Pose corner = upward_fisheye(glm::dvec3(0.6, 1.1, 0.7));
	// A frame with structure, so that a wrong pixel shows: a gradient in x and y.
	cv::Mat image(params.height, params.width, CV_32FC3);
	for (int y = 0; y < image.rows; y++) {
		for (int x = 0; x < image.cols; x++) {
			image.at<cv::Vec3f>(y, x) = cv::Vec3f(float(x) / 100.0f, float(y) / 100.0f, 1.0f);
		}
	}
	cv::Mat mask(mesh.atlas_height, mesh.atlas_width, CV_8UC1, cv::Scalar(255));
	mask(cv::Rect(0, 0, mesh.atlas_width / 3, mesh.atlas_height)) = 0; // an occluded third
	cv::Mat only(mesh.atlas_height, mesh.atlas_width, CV_8UC1, cv::Scalar(255));
	only(cv::Rect(0, 0, mesh.atlas_width, mesh.atlas_height / 2)) = 0; // "observed before": the lower half
	const int step = 2;
	TextureUpdateOptions options;
	CoarseTexture last = make_coarse_texture(mesh);
	options.policy = TextureUpdatePolicy::Last;
	update_coarse_texture(mesh, geometry, params, corner, image, &mask, &last, options);
	cv::Mat samples, visible;
	sample_coarse_texels(geometry, params, corner, image, &mask, only, step, options, &samples, &visible);
	int compared = 0, mismatched = 0;
	for (int y = 0; y < mesh.atlas_height; y++) {
		for (int x = 0; x < mesh.atlas_width; x++) {
			const bool expected = x % step == 0 && y % step == 0 && only.at<uint8_t>(y, x) != 0 && last.updated.at<uint8_t>(y, x) != 0;
			if ((visible.at<uint8_t>(y, x) != 0) != expected) {
				mismatched++;
			} else if (expected) {
				compared++;
				mismatched += cv::norm(samples.at<cv::Vec3f>(y, x) - last.color.at<cv::Vec3f>(y, x)) == 0.0 ? 0 : 1;
			}
		}
	}
	CHECK(compared > 1000);
	CHECK(mismatched == 0);
	// Wrong inputs: nothing is visible.
	sample_coarse_texels(geometry, params, corner, image, &mask, cv::Mat(), step, options, &samples, &visible);
	CHECK(cv::countNonZero(visible) == 0);
}

TEST_CASE("coarse update: from the frame's texel projection, the same as projecting on the spot") {
	const RoomMesh mesh = build(living_room());
	const TexelGeometry geometry = make_texel_geometry(mesh);
	const OmniParams params = test_rig().fisheye;
	cv::Mat image(params.height, params.width, CV_32FC3);
	for (int y = 0; y < image.rows; y++) {
		for (int x = 0; x < image.cols; x++) {
			image.at<cv::Vec3f>(y, x) = cv::Vec3f(float(x + 10) / 1100.0f, float(y + 10) / 1100.0f, 0.5f);
		}
	}
	cv::Mat mask(mesh.atlas_height, mesh.atlas_width, CV_8UC1, cv::Scalar(255));
	mask(cv::Rect(0, 0, mesh.atlas_width / 3, mesh.atlas_height)) = 0;
	// Upward views and tilted ones (towards walls, corners and the floor), so that charts' edges
	// and the image circle's rim cut through the texels.
	std::vector<Pose> poses = { upward_fisheye(glm::dvec3(2.5, 1.2, 2.0)), upward_fisheye(glm::dvec3(0.6, 1.1, 0.7)) };
	for (int k = 0; k < 4; k++) {
		Pose pose = upward_fisheye(glm::dvec3(1.0 + 0.8 * k, 1.0 + 0.2 * k, 1.0 + 0.5 * k));
		pose.rotation = glm::angleAxis(0.5 + 0.4 * k, glm::normalize(glm::dvec3(1.0, 0.3 * k, -0.5))) * pose.rotation;
		poses.push_back(pose);
	}
	CoarseTexture plain = make_coarse_texture(mesh), fast = make_coarse_texture(mesh);
	TexelProjection projection;
	LightingPairs pairs;
	pairs.step = 2;
	size_t updated = 0, pair_count = 0, skipped_tiles = 0;
	for (size_t k = 0; k < poses.size(); k++) {
		const cv::Mat *frame_mask = k % 2 ? &mask : nullptr;
		project_texels(geometry, params, poses[k], &projection);
		// The lighting pairs the update gathers: the plain samples of the texels observed before.
		const CoarseTexture before { fast.color.clone(), fast.observed.clone(), fast.quality.clone(), fast.updated.clone(), fast.saturated.clone(), fast.rgb_quality.clone() };
		cv::Mat before_samples, before_visible;
		sample_coarse_texels(geometry, params, poses[k], image, frame_mask, before.observed, pairs.step, TextureUpdateOptions(), &before_samples, &before_visible);
		const TextureUpdateStats a = update_coarse_texture(mesh, geometry, params, poses[k], image, frame_mask, &plain);
		const TextureUpdateStats b = update_coarse_texture(mesh, geometry, projection, params, poses[k], image, frame_mask, &fast, TextureUpdateOptions(), &pairs);
		const std::vector<LightingSample> &gathered = pairs.gather();
		CHECK(gathered.size() == size_t(cv::countNonZero(before_visible)));
		const LightingChange from_pairs = estimate_lighting_change(gathered, LightingOptions());
		const LightingChange from_samples = estimate_lighting_change(before, before_samples, before_visible, LightingOptions());
		CHECK(from_pairs.valid == (k > 0));
		CHECK(from_pairs.valid == from_samples.valid);
		CHECK(from_pairs.sample_count == from_samples.sample_count);
		CHECK(from_pairs.gain == from_samples.gain);
		pair_count += gathered.size();
		skipped_tiles += size_t(std::count(projection.tile_seen.begin(), projection.tile_seen.end(), uint8_t(0)));
		CHECK(a.texels_visible == b.texels_visible);
		CHECK(std::abs(double(a.texels_updated) - double(b.texels_updated)) <= 1e-4 * double(a.texels_updated));
		updated += a.texels_updated;

		// The lighting estimate's samples: exactly the plain ones.
		cv::Mat plain_samples, plain_visible, fast_samples, fast_visible;
		sample_coarse_texels(geometry, params, poses[k], image, frame_mask, plain.observed, 2, TextureUpdateOptions(), &plain_samples, &plain_visible);
		sample_coarse_texels(geometry, projection, params, poses[k], image, frame_mask, plain.observed, 2, TextureUpdateOptions(), &fast_samples,
				&fast_visible);
		CHECK(cv::norm(plain_visible, fast_visible, cv::NORM_INF) == 0.0);
		CHECK(cv::norm(plain_samples, fast_samples, cv::NORM_INF, plain_visible) == 0.0);
	}
	CHECK(updated > geometry.surface_texels);
	CHECK(pair_count > 10000);
	CHECK(skipped_tiles > 0); // the culling was exercised (and changed nothing above)
	// Qualities agree to rounding (a neighbour's pixel against its own point's projection); a
	// texel whose decision flips on that rounding is allowed, one in ten thousand.
	CHECK(cv::norm(plain.observed, fast.observed, cv::NORM_INF) == 0.0);
	int differing = 0;
	double worst_quality = 0.0;
	for (int y = 0; y < mesh.atlas_height; y++) {
		for (int x = 0; x < mesh.atlas_width; x++) {
			differing += plain.color.at<cv::Vec3f>(y, x) != fast.color.at<cv::Vec3f>(y, x) ? 1 : 0;
			const double q = plain.quality.at<float>(y, x);
			if (q > 0.0) {
				worst_quality = std::max(worst_quality, std::abs(fast.quality.at<float>(y, x) - q) / q);
			}
		}
	}
	CHECK(differing <= int(geometry.surface_texels / 10000));
	CHECK(worst_quality < 1e-4);
	MESSAGE("projection path: " << differing << " texels differ of " << geometry.surface_texels << ", worst relative quality difference " << worst_quality);
}

TEST_CASE("coarse update: HDR, a clipped value never replaces an unclipped one and is filled from a shorter exposure") {
	const RoomMesh mesh = build(living_room());
	const TexelGeometry geometry = make_texel_geometry(mesh);
	const OmniParams params = test_rig().fisheye;
	const Pose centre = upward_fisheye(glm::dvec3(2.5, 1.2, 2.0));
	TexelProjection projection;
	project_texels(geometry, params, centre, &projection);
	CoarseTexture texture = make_coarse_texture(mesh);
	// Linearised frames (CV_32FC3 radiance) with their saturation masks, all seen from one pose:
	// the same quality each time, so only the clipping decides.
	const auto frame = [&](float p_value, bool p_clipped) {
		return std::pair(cv::Mat(params.height, params.width, CV_32FC3, cv::Scalar::all(p_value)),
				cv::Mat(params.height, params.width, CV_8UC1, cv::Scalar(p_clipped ? 255 : 0)));
	};
	const Chart &ceiling = mesh.charts[mesh.floorplan.points.size() + 1];
	const cv::Point texel(ceiling.x + ceiling.w / 2, ceiling.y + ceiling.h / 2);
	const auto update = [&](const std::pair<cv::Mat, cv::Mat> &p_frame) {
		return update_coarse_texture(mesh, geometry, projection, params, centre, p_frame.first, nullptr, &texture, TextureUpdateOptions(), nullptr, &p_frame.second);
	};
	// A long exposure clips at 0.8: the texel holds that lower bound, marked clipped.
	CHECK(update(frame(0.8f, true)).texels_updated > 0);
	CHECK(texture.color.at<cv::Vec3f>(texel)[0] == doctest::Approx(0.8));
	CHECK(texture.saturated.at<uint8_t>(texel) == 255);
	// A longer one clips lower: the brighter bound stays.
	CHECK(update(frame(0.2f, true)).texels_updated == 0);
	CHECK(texture.color.at<cv::Vec3f>(texel)[0] == doctest::Approx(0.8));
	// A shorter exposure sees the true 3.0 unclipped: it replaces the clipped value.
	CHECK(update(frame(3.0f, false)).texels_updated > 0);
	CHECK(texture.color.at<cv::Vec3f>(texel)[0] == doctest::Approx(3.0));
	CHECK(texture.saturated.at<uint8_t>(texel) == 0);
	// A clipped observation does not replace it (a bound below the value says nothing).
	CHECK(update(frame(0.8f, true)).texels_updated == 0);
	CHECK(texture.color.at<cv::Vec3f>(texel)[0] == doctest::Approx(3.0));
	// An unclipped one as good still follows the scene (§4.6), as without HDR.
	CHECK(update(frame(2.0f, false)).texels_updated > 0);
	CHECK(texture.color.at<cv::Vec3f>(texel)[0] == doctest::Approx(2.0));
	// A bound well above the kept value proves it wrong (a light came on): it takes the bound,
	// clipped, for a shorter exposure to fill.
	CHECK(update(frame(2.4f, true)).texels_updated == 0); // within the noise margin
	CHECK(update(frame(2.6f, true)).texels_updated > 0);
	CHECK(texture.color.at<cv::Vec3f>(texel)[0] == doctest::Approx(2.6));
	CHECK(texture.saturated.at<uint8_t>(texel) == 255);
	CHECK(update(frame(20.0f, false)).texels_updated > 0);
	CHECK(texture.color.at<cv::Vec3f>(texel)[0] == doctest::Approx(20.0));
	// Without a mask nothing counts as clipped: the frame is taken as it is.
	CHECK(update_coarse_texture(mesh, geometry, projection, params, centre, frame(0.5f, true).first, nullptr, &texture).texels_updated > 0);
	CHECK(texture.color.at<cv::Vec3f>(texel)[0] == doctest::Approx(0.5));
}
