// The voxel-hashed colour TSDF of the dense SLAM stage (paper §4.2), against analytic scenes.

#include <io/opencv.h>

#include "slam/tsdf_integrate_simd.h"
#include "slam/tsdf_volume.h"
#include "slam_test_scenes.h"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <limits>
#include <numbers>

using namespace roomprobe;
using namespace slam_test;

namespace {

// The sphere of the accuracy tests, and 16 views around it (8 azimuths, 2 elevations).
Scene sphere_scene() {
	Scene scene;
	scene.spheres.push_back({ glm::dvec3(0.0, 0.0, 0.0), 0.3 });
	return scene;
}

void integrate_orbit(TsdfVolume *r_volume, const Scene &p_scene, const PinholeIntrinsics &p_camera, double p_distance, const std::vector<double> &p_elevations_deg, int p_azimuths) {
	for (double elevation : p_elevations_deg) {
		for (int i = 0; i < p_azimuths; i++) {
			const Frame f = render(p_scene, p_camera, orbit_pose(glm::dvec3(0.0), p_distance, 360.0 * i / p_azimuths, elevation));
			r_volume->integrate(f.depth, f.rgb, p_camera, f.world_from_camera);
		}
	}
}

float angle_deg(const cv::Vec3f &p_a, const cv::Vec3f &p_b) {
	const double c = double(p_a.dot(p_b)) / (cv::norm(p_a) * cv::norm(p_b));
	return float(glm::degrees(std::acos(std::clamp(c, -1.0, 1.0))));
}

// Raycast versus ground truth on the pixels away from surface edges.
struct Comparison {
	int truth_valid = 0, cast_valid = 0, both_interior = 0;
	int interior_holes = 0; // interior truth pixels the raycast missed
	int depth_within = 0; // |depth error| <= one voxel
	int normal_pixels = 0, normal_within = 0; // incidence < 60 deg; angle <= bound
	int color_within = 0; // every channel within the bound
	double max_point_error = 0.0;
};

// p_edge_px: pixels this close to an edge between surfaces are left out; p_border_px: and this
// close to the image border.
Comparison compare(const ModelMaps &p_maps, const Frame &p_truth, float p_voxel, float p_normal_bound_deg, int p_color_bound, int p_edge_px = 2, int p_border_px = 0) {
	Comparison c;
	const cv::Mat edges = edge_mask(p_truth, p_edge_px);
	for (int v = 0; v < p_truth.depth.rows; v++) {
		for (int u = 0; u < p_truth.depth.cols; u++) {
			if (u < p_border_px || v < p_border_px || u >= p_truth.depth.cols - p_border_px || v >= p_truth.depth.rows - p_border_px) {
				continue;
			}
			const float dt = p_truth.depth.at<float>(v, u), dc = p_maps.depth.at<float>(v, u);
			c.truth_valid += !std::isnan(dt);
			c.cast_valid += !std::isnan(dc);
			if (std::isnan(dt) || edges.at<uint8_t>(v, u)) {
				continue;
			}
			if (std::isnan(dc)) {
				c.interior_holes++;
				continue;
			}
			c.both_interior++;
			c.depth_within += std::fabs(dc - dt) <= p_voxel;
			if (p_truth.incidence_deg.at<float>(v, u) < 60.0f) {
				c.normal_pixels++;
				c.normal_within += angle_deg(p_maps.normals.at<cv::Vec3f>(v, u), p_truth.normals.at<cv::Vec3f>(v, u)) <= p_normal_bound_deg;
			}
			const cv::Vec3b a = p_maps.colors.at<cv::Vec3b>(v, u), b = p_truth.rgb.at<cv::Vec3b>(v, u);
			bool color_ok = true;
			for (int k = 0; k < 3; k++) {
				color_ok &= std::abs(int(a[k]) - int(b[k])) <= p_color_bound;
			}
			c.color_within += color_ok;
		}
	}
	return c;
}

} // namespace

TEST_CASE("TSDF of a sphere: raycast depth, normals, colour and coverage match the analytic sphere") {
	const PinholeIntrinsics camera = rig_camera();
	const Scene scene = sphere_scene();
	TsdfOptions options;
	TsdfVolume volume(options);
	integrate_orbit(&volume, scene, camera, 1.0, { 25.0, -15.0 }, 8);

	// A pose between the integrated ones.
	const Frame truth = render(scene, camera, orbit_pose(glm::dvec3(0.0), 0.9, 22.5, 10.0));
	ModelMaps maps;
	volume.raycast(camera, truth.world_from_camera, &maps);
	REQUIRE(maps.points.type() == CV_32FC3);
	REQUIRE(maps.normals.type() == CV_32FC3);
	REQUIRE(maps.colors.type() == CV_8UC3);
	REQUIRE(maps.depth.type() == CV_32FC1);
	CHECK(maps.camera.fx == camera.fx);

	// Bounds, derived:
	// - depth: the zero crossing is interpolated between voxels 1 cm apart; one voxel.
	// - normals: each reading gives the distance to its tangent plane; one voxel off a sphere of
	//   radius R, a view slanted by the most the volume accepts (72 deg: min_slope 0.3) reads the
	//   plane at s = h tan 72 = 3.1 cm from the voxel's foot point, where the plane and the sphere
	//   part by s^2 / 2R = 1.6 mm. Across the 2-voxel (2 cm) central difference that turns the
	//   gradient by up to atan(1.6 / 20) = 4.6 deg: 5 deg (checked where this view is within
	//   60 deg of head-on; beyond, the sphere's own silhouette region is thin in pixels).
	// - colour: colour is fused within 1 cm of the surface and interpolated between voxels, so it
	//   is the pattern up to one voxel away: 800 levels/m * 0.01 m = 8 levels, + 2 for rounding.
	const float voxel = options.voxel_size_m;
	const int color_bound = int(PATTERN_MAX_GRADIENT * voxel) + 2;
	const Comparison c = compare(maps, truth, voxel, 5.0f, color_bound);
	MESSAGE("truth " << c.truth_valid << " cast " << c.cast_valid << " interior " << c.both_interior << " holes " << c.interior_holes << " depth ok " << c.depth_within << " normals ok " << c.normal_within << "/" << c.normal_pixels << " colour ok " << c.color_within);
	REQUIRE(c.both_interior > 50000);
	CHECK(c.depth_within >= 0.99 * c.both_interior);
	CHECK(c.normal_within >= 0.99 * c.normal_pixels);
	CHECK(c.color_within >= 0.99 * c.both_interior);
	// No holes: every interior pixel of the sphere is hit, and the counts differ by at most the
	// silhouette band (pixels within 2 px of the outline, 2 * 2 * pi * r_px at most).
	CHECK(c.interior_holes == 0);
	const double radius_px = camera.fx * 0.3 / std::sqrt(0.9 * 0.9 - 0.3 * 0.3);
	CHECK(std::abs(c.cast_valid - c.truth_valid) <= 4.0 * std::numbers::pi * radius_px);

	// Points are in the world frame, on the sphere, and agree with depth.
	int checked = 0, on_sphere = 0;
	for (int v = 0; v < maps.depth.rows; v += 7) {
		for (int u = 0; u < maps.depth.cols; u += 7) {
			const float d = maps.depth.at<float>(v, u);
			if (std::isnan(d)) {
				CHECK(std::isnan(maps.points.at<cv::Vec3f>(v, u)[0]));
				continue;
			}
			const cv::Vec3f p = maps.points.at<cv::Vec3f>(v, u);
			checked++;
			on_sphere += std::fabs(glm::length(glm::vec3(p[0], p[1], p[2])) - 0.3f) <= voxel;
			const glm::dvec3 camera_point = transform_point(inverse(truth.world_from_camera), glm::dvec3(p[0], p[1], p[2]));
			CHECK(camera_point.z == doctest::Approx(d).epsilon(1e-4));
		}
	}
	CHECK(on_sphere >= 0.99 * checked);
}

TEST_CASE("TSDF of a box on a floor: depth within one voxel away from edges, no holes") {
	const PinholeIntrinsics camera = rig_camera(1); // 320 x 240: the same field of view, faster
	Scene scene;
	scene.boxes.push_back({ glm::dvec3(-0.25, -0.3, -0.2), glm::dvec3(0.25, 0.1, 0.2) });
	scene.boxes.push_back({ glm::dvec3(-1.0, -0.4, -1.0), glm::dvec3(1.0, -0.3, 1.0) }); // the floor
	TsdfOptions options;
	TsdfVolume volume(options);
	for (int i = 0; i < 8; i++) {
		const Frame f = render(scene, camera, orbit_pose(glm::dvec3(0.0, -0.2, 0.0), 1.4, 45.0 * i, 35.0));
		volume.integrate(f.depth, f.rgb, camera, f.world_from_camera);
	}
	const Frame truth = render(scene, camera, orbit_pose(glm::dvec3(0.0, -0.2, 0.0), 1.3, 70.0, 30.0));
	ModelMaps maps;
	volume.raycast(camera, truth.world_from_camera, &maps);
	// Near a convex edge of the box, the voxels inside get distances to both faces' planes from
	// the views that see either face; the one to the other face is too negative, which pulls the
	// surface outwards up to one truncation band from the edge. Left out: pixels that close to an
	// edge, truncation * fx / (nearest depth) pixels.
	double nearest = 1e9;
	for (int v = 0; v < truth.depth.rows; v++) {
		for (int u = 0; u < truth.depth.cols; u++) {
			const float d = truth.depth.at<float>(v, u);
			nearest = std::isnan(d) ? nearest : std::min(nearest, double(d));
		}
	}
	const int edge_px = int(std::ceil(options.truncation_m * camera.fx / nearest));
	const Comparison c = compare(maps, truth, options.voxel_size_m, 90.0f, 255, edge_px);
	MESSAGE("edge band " << edge_px << " px: truth " << c.truth_valid << " cast " << c.cast_valid << " interior " << c.both_interior << " holes " << c.interior_holes << " depth ok " << c.depth_within);
	REQUIRE(c.both_interior > 10000);
	CHECK(c.depth_within >= 0.99 * c.both_interior);
	CHECK(c.interior_holes == 0);
	// The floor's far corners lie outside the integrated views' frusta only at the image border.
	CHECK(c.cast_valid >= 0.97 * c.truth_valid);
}

TEST_CASE("TSDF raycast skips empty space") {
	const PinholeIntrinsics camera = rig_camera(1);
	Scene scene;
	scene.spheres.push_back({ glm::dvec3(-1.2, 0.0, 0.0), 0.2 });
	scene.spheres.push_back({ glm::dvec3(1.2, 0.0, 0.0), 0.2 });
	TsdfOptions options;
	TsdfVolume volume(options);
	for (double x : { -1.2, 1.2 }) {
		const Frame f = render(scene, camera, look_at(glm::dvec3(x, 0.0, 1.0), glm::dvec3(x, 0.0, 0.0)));
		volume.integrate(f.depth, f.rgb, camera, f.world_from_camera);
	}
	const TsdfStats stats = volume.stats();
	REQUIRE(stats.allocated_blocks > 0);

	SUBCASE("a view between the spheres: rays cross the allocated bounds, no block projects there") {
		const Pose pose = look_at(glm::dvec3(0.0, 0.0, 1.0), glm::dvec3(0.0, 0.0, 0.0));
		CHECK(render(scene, camera, pose).ids.at<int>(120, 160) == -1);
		ModelMaps maps;
		RaycastStats rs;
		volume.raycast(camera, pose, &maps, &rs);
		CHECK(rs.hit_pixels == 0);
		CHECK(cv::countNonZero(maps.depth == maps.depth) == 0); // all NaN
		// No block projects into this view, so no ray is marched at all; even without that
		// pruning, a traversal that visits every block the ray crosses once takes at most
		// |dx| + |dy| + |dz| <= sqrt(3) L / block + 3 steps over a length L inside the bounds.
		const float block = 8.0f * options.voxel_size_m;
		const float diagonal = glm::length(stats.bounds_max - stats.bounds_min);
		const double mean_steps = double(rs.steps) / (camera.width * camera.height);
		MESSAGE("mean steps per pixel " << mean_steps);
		CHECK(mean_steps <= std::sqrt(3.0) * diagonal / block + 3.0);
	}
	SUBCASE("a view away from everything: no step at all") {
		ModelMaps maps;
		RaycastStats rs;
		volume.raycast(camera, look_at(glm::dvec3(0.0, 0.0, 1.0), glm::dvec3(0.0, 0.0, 3.0)), &maps, &rs);
		CHECK(rs.hit_pixels == 0);
		CHECK(rs.steps == 0);
		CHECK(cv::countNonZero(maps.depth == maps.depth) == 0);
	}
}

TEST_CASE("TSDF memory cap: evicts far from the keep-point, never the view") {
	const PinholeIntrinsics camera = rig_camera(1);
	Scene scene;
	scene.boxes.push_back({ glm::dvec3(-3.0, -1.0, -0.1), glm::dvec3(3.0, 1.0, 0.0) }); // a wall, facing +z
	TsdfOptions options;
	options.max_blocks = 900; // the keep-point's surroundings and one view (each ~360 blocks) fit
	const glm::dvec3 keep(-2.0, 0.0, 0.0); // on the wall, seen by the first frame only
	TsdfVolume volume(options);
	volume.set_keep_points({ keep });
	long long evicted = 0;
	Frame last;
	for (double x = -2.0; x <= 2.0 + 1e-9; x += 0.25) {
		last = render(scene, camera, look_at(glm::dvec3(x, 0.0, 1.0), glm::dvec3(x, 0.0, 0.0)));
		const IntegrationStats s = volume.integrate(last.depth, last.rgb, camera, last.world_from_camera);
		evicted += s.evicted_blocks;
		CHECK(volume.stats().allocated_blocks <= options.max_blocks);
		CHECK(s.dropped_blocks == 0); // one view fits
	}
	const TsdfStats stats = volume.stats();
	MESSAGE("allocated " << stats.allocated_blocks << " evicted " << stats.evicted_blocks_total << " bytes " << stats.bytes_used);
	CHECK(evicted > 0);
	CHECK(stats.evicted_blocks_total == evicted);
	CHECK(stats.bytes_used <= size_t(options.max_blocks) * (512 * sizeof(TsdfVoxel) + 64) + 4 * 1024 * 1024);
	// The surface at the keep-point survived.
	float tsdf;
	glm::vec3 rgb;
	REQUIRE(volume.sample_tsdf(glm::vec3(keep), &tsdf, &rgb));
	CHECK(std::fabs(tsdf) * options.truncation_m <= options.voxel_size_m);
	// Blocks midway were evicted (they are the farthest from the keep-point outside the view).
	CHECK_FALSE(volume.sample_tsdf(glm::vec3(0.5f, 0.0f, 0.0f), &tsdf, &rgb));
	// The current view was kept whole. Only this frame saw the right and top and bottom borders;
	// a hit there needs the voxels within one voxel of it (2.6 px at 1 m) seen, so a border of
	// 4 px is left out.
	ModelMaps maps;
	volume.raycast(camera, last.world_from_camera, &maps);
	const int border_px = int(std::ceil(options.voxel_size_m * camera.fx / 1.0f)) + 1;
	const Comparison c = compare(maps, last, options.voxel_size_m, 90.0f, 255, 2, border_px);
	CHECK(c.both_interior > 0.9 * (camera.width - 2 * border_px) * (camera.height - 2 * border_px));
	CHECK(c.interior_holes == 0);
	CHECK(c.depth_within >= 0.99 * c.both_interior);

	SUBCASE("a cap smaller than one view: blocks are dropped, the cap holds") {
		TsdfOptions tiny = options;
		tiny.max_blocks = 50;
		TsdfVolume small(tiny);
		const IntegrationStats s = small.integrate(last.depth, last.rgb, camera, last.world_from_camera);
		CHECK(s.dropped_blocks > 0);
		CHECK(small.stats().allocated_blocks == 50);
		CHECK(small.stats().dropped_blocks_total == s.dropped_blocks);
	}
}

TEST_CASE("TSDF ignores NaN and zero depth") {
	const PinholeIntrinsics camera = rig_camera(1);
	const cv::Mat rgb(camera.height, camera.width, CV_8UC3, cv::Scalar::all(128));
	TsdfVolume volume;
	const Pose pose = look_at(glm::dvec3(0.0, 0.0, 1.0), glm::dvec3(0.0));
	for (float value : { std::numeric_limits<float>::quiet_NaN(), 0.0f }) {
		const cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(value));
		const IntegrationStats s = volume.integrate(depth, rgb, camera, pose);
		CHECK(s.valid_pixels == 0);
		CHECK(s.allocated_blocks == 0);
		CHECK(volume.stats().allocated_blocks == 0);
		CHECK(volume.take_dirty_blocks().empty());
	}
	// Half the frame invalid: only the other half is used.
	const Frame f = render(sphere_scene(), camera, pose);
	cv::Mat depth = f.depth.clone();
	depth.colRange(0, camera.width / 2).setTo(0.0f);
	const IntegrationStats s = volume.integrate(depth, f.rgb, camera, pose);
	CHECK(s.valid_pixels == cv::countNonZero(depth > 0.0f));
	ModelMaps maps;
	volume.raycast(camera, pose, &maps);
	CHECK(cv::countNonZero(maps.depth.colRange(0, camera.width / 2 - 8) == maps.depth.colRange(0, camera.width / 2 - 8)) == 0);
	CHECK(cv::countNonZero(maps.depth.colRange(camera.width / 2 + 8, camera.width) == maps.depth.colRange(camera.width / 2 + 8, camera.width)) > 1000);
}

TEST_CASE("TSDF dirty blocks, bounds, reset") {
	const PinholeIntrinsics camera = rig_camera(1);
	TsdfVolume volume;
	const Frame f = render(sphere_scene(), camera, orbit_pose(glm::dvec3(0.0), 1.0, 0.0, 0.0));
	const IntegrationStats s = volume.integrate(f.depth, f.rgb, camera, f.world_from_camera);
	const std::vector<glm::ivec3> dirty = volume.take_dirty_blocks();
	// Blocks in the band whose voxels all lie further than the truncation behind the surface
	// stay untouched (a block reaches the band at one corner only).
	CHECK(int(dirty.size()) <= s.allocated_blocks);
	CHECK(double(dirty.size()) >= 0.9 * s.allocated_blocks);
	CHECK(volume.take_dirty_blocks().empty());
	const TsdfStats stats = volume.stats();
	CHECK(stats.allocated_blocks == s.allocated_blocks);
	// The bounds hold the visible cap of the sphere and its truncation band.
	for (int a = 0; a < 3; a++) {
		CHECK(stats.bounds_min[a] <= (a == 2 ? 0.05f : -0.28f));
		CHECK(stats.bounds_max[a] >= (a == 2 ? 0.3f + 0.04f : 0.28f));
		CHECK(stats.bounds_max[a] - stats.bounds_min[a] <= 0.6f + 2.0f * 0.04f + 2.0f * 0.08f);
	}
	volume.reset();
	CHECK(volume.stats().allocated_blocks == 0);
	CHECK(int(volume.take_dirty_blocks().size()) == s.allocated_blocks); // every freed block changed
	float tsdf;
	CHECK_FALSE(volume.sample_tsdf(glm::vec3(0.0f, 0.0f, 0.3f), &tsdf, nullptr));
}

TEST_CASE("TSDF timing at 640x480 (prints, asserts nothing)" * doctest::skip()) {
	const PinholeIntrinsics camera = rig_camera();
	Scene scene;
	scene.spheres.push_back({ glm::dvec3(0.0), 0.3 });
	scene.boxes.push_back({ glm::dvec3(-1.5, -0.4, -1.5), glm::dvec3(1.5, -0.3, 1.5) }); // floor
	scene.boxes.push_back({ glm::dvec3(-1.5, -0.4, -1.6), glm::dvec3(1.5, 1.2, -1.5) }); // wall
	const Frame f = render(scene, camera, orbit_pose(glm::dvec3(0.0), 1.2, 10.0, 20.0));
	using clock = std::chrono::steady_clock;
	auto ms = [](clock::time_point p_a, clock::time_point p_b) { return std::chrono::duration<double, std::milli>(p_b - p_a).count(); };
	auto cpu_ms = [](std::clock_t p_a, std::clock_t p_b) { return 1000.0 * double(p_b - p_a) / CLOCKS_PER_SEC; };
	const int default_threads = cv::getNumThreads();
	for (int threads : { 1, default_threads }) {
		cv::setNumThreads(threads);
		TsdfVolume volume;
		for (int i = 0; i < 5; i++) {
			const auto t0 = clock::now();
			const std::clock_t c0 = std::clock();
			const IntegrationStats s = volume.integrate(f.depth, f.rgb, camera, f.world_from_camera);
			const auto t1 = clock::now();
			const std::clock_t c1 = std::clock();
			ModelMaps maps;
			RaycastStats rs;
			volume.raycast(camera, f.world_from_camera, &maps, &rs);
			const auto t2 = clock::now();
			const std::clock_t c2 = std::clock();
			std::printf("%d thread(s), frame %d: integrate %.1f ms wall / %.1f ms cpu (%d valid px, %d visible blocks, %d new), raycast %.1f ms wall / %.1f ms cpu (%d hits, %.1f steps/px)\n", threads, i, ms(t0, t1), cpu_ms(c0, c1), s.valid_pixels, s.visible_blocks, s.allocated_blocks, ms(t1, t2), cpu_ms(c1, c2), rs.hit_pixels, double(rs.steps) / (camera.width * camera.height));
		}
		std::printf("allocated %d blocks, %.1f MB\n", volume.stats().allocated_blocks, double(volume.stats().bytes_used) / 1e6);
	}
	cv::setNumThreads(default_threads);
}

TEST_CASE("TSDF raycast within per-pixel search intervals finds the same surface in fewer steps, and nothing outside them") {
	const PinholeIntrinsics camera = rig_camera(1);
	Scene scene;
	scene.spheres.push_back({ glm::dvec3(0.0, 0.0, 0.0), 0.3 });
	TsdfVolume volume;
	const Pose pose = look_at(glm::dvec3(0.0, 0.2, 1.5), glm::dvec3(0.0, 0.0, 0.0));
	const Frame f = render(scene, camera, pose);
	volume.integrate(f.depth, f.rgb, camera, pose);
	ModelMaps full, searched, outside;
	RaycastStats full_stats, searched_stats, outside_stats;
	volume.raycast(camera, pose, &full, &full_stats);
	// Intervals of +-8 cm around the rendered depth; NaN (the whole range) where there is none.
	cv::Mat around(camera.height, camera.width, CV_32FC2), beyond(camera.height, camera.width, CV_32FC2);
	for (int v = 0; v < camera.height; v++) {
		for (int u = 0; u < camera.width; u++) {
			const float d = f.depth.at<float>(v, u);
			const bool has = d > 0.0f;
			const float nan = std::numeric_limits<float>::quiet_NaN();
			around.at<cv::Vec2f>(v, u) = has ? cv::Vec2f(d - 0.08f, d + 0.08f) : cv::Vec2f(nan, nan);
			beyond.at<cv::Vec2f>(v, u) = has ? cv::Vec2f(d + 0.2f, d + 0.4f) : cv::Vec2f(nan, nan);
		}
	}
	volume.raycast(camera, pose, around, &searched, &searched_stats);
	volume.raycast(camera, pose, beyond, &outside, &outside_stats);
	REQUIRE(full_stats.hit_pixels > 1000);
	// Every pixel found is found by the full march too; only grazing pixels at the silhouette, whose
	// crossing lies more than 8 cm behind the reading, are lost.
	CHECK(cv::countNonZero((searched.depth == searched.depth) & (full.depth != full.depth)) == 0);
	CHECK(searched_stats.hit_pixels >= 0.99 * full_stats.hit_pixels);
	cv::Mat difference;
	cv::absdiff(full.depth, searched.depth, difference);
	double worst = 0.0;
	cv::minMaxIdx(difference, nullptr, &worst, nullptr, nullptr, searched.depth == searched.depth);
	// The same crossing: another start moves only the refinement's bracket, within half a voxel.
	CHECK(worst < 0.5 * TsdfOptions().voxel_size_m);
	CHECK(searched_stats.steps < full_stats.steps);
	CHECK(outside_stats.hit_pixels == 0); // the sphere's back is never a + to - crossing
}

// Bit for bit: NaN where both missed, else the same float bits.
bool same_bits(const cv::Mat &p_a, const cv::Mat &p_b) {
	return p_a.size() == p_b.size() && p_a.type() == p_b.type() && p_a.isContinuous() && p_b.isContinuous() &&
			std::memcmp(p_a.data, p_b.data, p_a.total() * p_a.elemSize()) == 0;
}

TEST_CASE("TSDF raycast: rays marched together on a thread give each ray's own march, bit for bit, with and without normals") {
	const PinholeIntrinsics camera = rig_camera(1);
	const Scene scene = sphere_scene();
	TsdfVolume volume;
	integrate_orbit(&volume, scene, camera, 1.0, { 25.0, -15.0 }, 8);
	const Pose pose = orbit_pose(glm::dvec3(0.0), 0.9, 22.5, 10.0);
	const TsdfOptions &options = volume.options();
	for (const bool normals : { true, false }) {
		CAPTURE(normals);
		ModelMaps maps;
		RaycastStats stats;
		volume.raycast(camera, pose, options.min_depth_m, options.max_depth_m, &maps, &stats, normals);
		// The same pixels one ray at a time, each within its cell's depth range as the volume's raycast limits it.
		const cv::Mat ranges = volume.depth_ranges(camera, pose, options.min_depth_m, options.max_depth_m);
		const float nan = std::numeric_limits<float>::quiet_NaN();
		cv::Mat points(camera.height, camera.width, CV_32FC3, cv::Scalar::all(nan)), normal_map(camera.height, camera.width, CV_32FC3, cv::Scalar::all(nan));
		cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar::all(nan));
		cv::Mat colors(camera.height, camera.width, CV_8UC3, cv::Scalar::all(0));
		TsdfRayParams ray;
		ray.origin = glm::vec3(pose.translation);
		ray.world_from_camera_rotation = glm::mat3(glm::mat3_cast(glm::quat(pose.rotation))); // as the volume makes it, in float
		ray.bounds_min = volume.stats().bounds_min;
		ray.bounds_max = volume.stats().bounds_max;
		ray.normals = normals;
		long long steps = 0;
		int hits = 0;
		for (int v = 0; v < camera.height; v++) {
			for (int u = 0; u < camera.width; u++) {
				const cv::Vec2f range = ranges.at<cv::Vec2f>(v / TsdfVolume::DEPTH_RANGE_CELL_PX, u / TsdfVolume::DEPTH_RANGE_CELL_PX);
				if (!(range[0] <= range[1])) {
					continue;
				}
				TsdfRayParams pixel = ray;
				pixel.min_depth_m = std::max(options.min_depth_m, range[0]);
				pixel.max_depth_m = std::min(options.max_depth_m, range[1]);
				TsdfRayHit hit;
				int n = 0;
				const bool found = tsdf_raycast_pixel(volume.view(), pixel, camera, u, v, &hit, &n);
				steps += n;
				if (!found) {
					continue;
				}
				hits++;
				points.at<cv::Vec3f>(v, u) = cv::Vec3f(hit.point.x, hit.point.y, hit.point.z);
				normal_map.at<cv::Vec3f>(v, u) = cv::Vec3f(hit.normal.x, hit.normal.y, hit.normal.z);
				depth.at<float>(v, u) = hit.depth;
				colors.at<cv::Vec3b>(v, u) = cv::Vec3b(cv::saturate_cast<uint8_t>(hit.rgb.x), cv::saturate_cast<uint8_t>(hit.rgb.y), cv::saturate_cast<uint8_t>(hit.rgb.z));
			}
		}
		REQUIRE(hits > 10000);
		CHECK(stats.hit_pixels == hits);
		CHECK(stats.steps == steps);
		CHECK(same_bits(maps.points, points));
		CHECK(same_bits(maps.normals, normal_map));
		CHECK(same_bits(maps.depth, depth));
		CHECK(same_bits(maps.colors, colors));
	}
}

TEST_CASE("TSDF integration's skipped blocks and voxels: every voxel as the plain path leaves it, and a removed object is still carved away") {
	const PinholeIntrinsics camera = rig_camera(1);
	Scene with_ball;
	with_ball.boxes.push_back({ glm::dvec3(-3.0, -1.0, -0.1), glm::dvec3(3.0, 1.0, 0.0) }); // a wall, facing +z
	with_ball.boxes.push_back({ glm::dvec3(-3.0, -1.1, -0.1), glm::dvec3(3.0, -1.0, 3.0) }); // a floor
	with_ball.spheres.push_back({ glm::dvec3(0.0, -0.6, 0.8), 0.25 });
	Scene without_ball = with_ball;
	without_ball.spheres.clear();
	TsdfOptions options;
	options.max_weight = 2; // free space saturates within a few frames
	options.max_color_weight = 2;
	TsdfOptions plain_options = options;
	plain_options.skip_unchanged = false;
	TsdfVolume fast(options), plain(plain_options);
	long long visible = 0, updated = 0;
	auto integrate_both = [&](const Scene &p_scene, const Pose &p_pose) {
		const Frame f = render(p_scene, camera, p_pose);
		const IntegrationStats a = fast.integrate(f.depth, f.rgb, camera, f.world_from_camera);
		const IntegrationStats b = plain.integrate(f.depth, f.rgb, camera, f.world_from_camera);
		CHECK(a.visible_blocks == b.visible_blocks);
		CHECK(a.allocated_blocks == b.allocated_blocks);
		CHECK(b.updated_blocks == b.visible_blocks);
		visible += a.visible_blocks;
		updated += a.updated_blocks;
	};
	// The ball seen from several sides, then gone, then seen again from around and from where it stood.
	for (int i = 0; i < 6; i++) {
		integrate_both(with_ball, look_at(glm::dvec3(-0.6 + 0.24 * i, 0.1, 2.2), glm::dvec3(0.0, -0.5, 0.6)));
	}
	for (int i = 0; i < 8; i++) {
		integrate_both(without_ball, look_at(glm::dvec3(0.6 - 0.15 * i, -0.5, 2.4), glm::dvec3(0.0, -0.6, 0.0))); // the wall behind it head-on
	}
	integrate_both(without_ball, look_at(glm::dvec3(0.0, -0.6, 0.8), glm::dvec3(0.0, -0.6, 0.0)));
	MESSAGE("blocks updated " << updated << " of " << visible << " in view");
	CHECK(updated < visible);

	const std::vector<glm::ivec3> blocks = fast.allocated_blocks();
	REQUIRE(blocks == plain.allocated_blocks());
	int differing = 0;
	for (const glm::ivec3 &b : blocks) {
		const TsdfVoxel *x = fast.find_block(b), *y = plain.find_block(b);
		for (int i = 0; i < TSDF_BLOCK_VOXELS; i++) {
			differing += x[i].tsdf != y[i].tsdf || x[i].weight != y[i].weight || x[i].color_weight != y[i].color_weight || x[i].r != y[i].r || x[i].g != y[i].g || x[i].b != y[i].b;
		}
	}
	CHECK(differing == 0);
	// Where the ball's front stood is free space again (positive), the wall behind it a surface.
	for (TsdfVolume *volume : { &fast, &plain }) {
		float tsdf;
		glm::vec3 rgb;
		REQUIRE(volume->sample_tsdf(glm::vec3(0.0f, -0.6f, 1.05f), &tsdf, &rgb));
		CHECK(tsdf > 0.5f);
		REQUIRE(volume->sample_tsdf(glm::vec3(0.0f, -0.6f, 0.0f), &tsdf, &rgb));
		CHECK(std::fabs(tsdf) * options.truncation_m <= options.voxel_size_m);
	}
}

TEST_CASE("TSDF integration eight voxels at a time (AVX2): every voxel and every dirty block as the scalar kernel leaves them") {
	if (!tsdf_simd_available()) {
		MESSAGE("this CPU has no AVX2: only the scalar kernel runs here");
		return;
	}
	const PinholeIntrinsics camera = rig_camera(1);
	Scene scene;
	scene.boxes.push_back({ glm::dvec3(-3.0, -1.0, -0.1), glm::dvec3(3.0, 1.0, 0.0) }); // a wall
	scene.boxes.push_back({ glm::dvec3(-3.0, -1.1, -0.1), glm::dvec3(3.0, -1.0, 3.0) }); // a floor
	scene.spheres.push_back({ glm::dvec3(0.0, -0.6, 0.8), 0.25 });
	for (const bool skip : { true, false }) {
		CAPTURE(skip);
		TsdfOptions options;
		options.max_weight = 3; // saturated free space within a few frames: the early exit that needs it runs
		options.max_color_weight = 2;
		options.max_depth_m = 2.6f; // part of the wall is beyond it
		options.skip_unchanged = skip;
		TsdfOptions scalar_options = options;
		scalar_options.simd = false;
		TsdfVolume simd(options), scalar(scalar_options);
		cv::RNG rng(7);
		for (int i = 0; i < 8; i++) {
			Frame f = render(scene, camera, look_at(glm::dvec3(-0.5 + 0.14 * i, 0.1 - 0.05 * i, 2.3 - 0.1 * i), glm::dvec3(0.0, -0.6, 0.4)));
			// Sensor-like readings: noise growing with depth, holes, and zeros (no reading).
			for (int v = 0; v < f.depth.rows; v++) {
				for (int u = 0; u < f.depth.cols; u++) {
					float &d = f.depth.at<float>(v, u);
					const double r = rng.uniform(0.0, 1.0);
					d = r < 0.03 ? std::numeric_limits<float>::quiet_NaN() : r < 0.05 ? 0.0f : d + float(rng.gaussian(0.002 * d * d));
				}
			}
			const IntegrationStats a = simd.integrate(f.depth, f.rgb, camera, f.world_from_camera);
			const IntegrationStats b = scalar.integrate(f.depth, f.rgb, camera, f.world_from_camera);
			CHECK(a.visible_blocks == b.visible_blocks);
			CHECK(a.updated_blocks == b.updated_blocks);
			CHECK(a.allocated_blocks == b.allocated_blocks);
			CHECK(simd.take_dirty_blocks() == scalar.take_dirty_blocks());
		}
		const std::vector<glm::ivec3> blocks = simd.allocated_blocks();
		REQUIRE(blocks == scalar.allocated_blocks());
		long long differing = 0, observed = 0, coloured = 0, saturated = 0;
		for (const glm::ivec3 &block : blocks) {
			const TsdfVoxel *x = simd.find_block(block), *y = scalar.find_block(block);
			for (int i = 0; i < TSDF_BLOCK_VOXELS; i++) {
				differing += std::memcmp(&x[i], &y[i], sizeof(TsdfVoxel)) != 0;
				observed += y[i].weight > 0;
				coloured += y[i].color_weight > 0;
				saturated += y[i].tsdf == 1.0f && y[i].weight == options.max_weight * TSDF_WEIGHT_UNIT;
			}
		}
		MESSAGE(observed << " voxels observed, " << coloured << " coloured, " << saturated << " saturated free space");
		CHECK(observed > 100000); // the paths under test really ran
		CHECK(coloured > 10000);
		CHECK(saturated > 1000);
		CHECK(differing == 0);
	}
}

TEST_CASE("TSDF kernels' inline rounding, fmin and fmax agree with the standard library") {
	// Every colour average the update can form (weights up to 300), halves, and values next to them.
	int mismatches = 0;
	for (int cw = 0; cw <= 300; cw++) {
		for (int old = 0; old <= 255; old += 3) {
			for (int px = 0; px <= 255; px++) {
				const float q = (float(old) * float(cw) + float(px)) / (float(cw) + 1.0f);
				mismatches += tsdf_round_positive(q) != int(std::lround(q));
			}
		}
	}
	for (float x : { 0.0f, 0.5f, 1.5f, 2.5f, 254.5f, 0.49999997f, 1.4999999f, 31.999998f, 32.0f, 1e6f + 0.5f }) {
		for (float y : { x, std::nextafter(x, 0.0f), std::nextafter(x, 1e9f) }) {
			mismatches += tsdf_round_positive(y) != int(std::lround(y));
		}
	}
	CHECK(mismatches == 0);
	const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
	const float values[] = { -inf, -2.0f, -0.5f, 0.0f, 0.25f, 3.0f, inf, nan };
	for (float a : values) {
		for (float b : values) {
			const float lo = tsdf_fmin(a, b), hi = tsdf_fmax(a, b);
			const float lo_std = std::fmin(a, b), hi_std = std::fmax(a, b);
			CHECK((lo == lo_std || (std::isnan(lo) && std::isnan(lo_std))));
			CHECK((hi == hi_std || (std::isnan(hi) && std::isnan(hi_std))));
		}
	}
}
