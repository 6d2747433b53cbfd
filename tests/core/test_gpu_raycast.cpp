// TSDF raycasts on a Vulkan device (slam/tsdf_raycast_gpu.h) against the CPU's, pixel by pixel,
// on the synthetic living room, on gpu_test_device() (lavapipe in CI).
//
// The tolerance: the kernel runs tsdf_raycast_pixel's operations in the same order with no fused
// multiply-adds, so where the device's division and square root are correctly rounded (lavapipe's
// are) the maps are the CPU's bit for bit, and the test holds lavapipe to that. Vulkan allows a
// GPU 2.5 ulp in a division and more in a square root: each sample then moves by float rounding
// (about 1e-7 of its distance), which moves a refined hit by as much (0.5 um at 4 m) unless a
// sample lands within that of a voxel's edge, a block's edge or the tsdf's sign change, where the
// march takes another step. On other devices the test allows those: depth within 1e-5 of itself,
// normals within 1e-4, colours within 1, and at most 1 pixel in 500 beyond that.

#include "gpu_test_device.h"
#include "gpu_test_fusion.h"
#include "slam/tsdf_volume.h"
#include "synth_test_frames.h"

#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <memory>

using namespace roomprobe;
using namespace synth_frames;

namespace {

struct MapDifference {
	int pixels = 0, hits = 0;
	int other = 0; // a hit on one side only, or beyond the tolerances above
	int bits_differ = 0; // any value differs
	long long steps_cpu = 0, steps_gpu = 0;
};

bool same_bits(const cv::Mat &p_a, const cv::Mat &p_b, int p_v, int p_u) {
	const size_t bytes = p_a.elemSize();
	return std::memcmp(p_a.ptr(p_v) + size_t(p_u) * bytes, p_b.ptr(p_v) + size_t(p_u) * bytes, bytes) == 0;
}

MapDifference compare_maps(const ModelMaps &p_cpu, const ModelMaps &p_gpu, bool p_normals) {
	MapDifference out;
	for (int v = 0; v < p_cpu.depth.rows; v++) {
		for (int u = 0; u < p_cpu.depth.cols; u++) {
			out.pixels++;
			const float a = p_cpu.depth.at<float>(v, u), b = p_gpu.depth.at<float>(v, u);
			const bool bits = same_bits(p_cpu.depth, p_gpu.depth, v, u) && same_bits(p_cpu.points, p_gpu.points, v, u) &&
					same_bits(p_cpu.normals, p_gpu.normals, v, u) && same_bits(p_cpu.colors, p_gpu.colors, v, u);
			out.bits_differ += bits ? 0 : 1;
			if (std::isnan(a) != std::isnan(b)) {
				out.other++;
				continue;
			}
			if (std::isnan(a)) {
				continue;
			}
			out.hits++;
			bool close = std::abs(a - b) <= 1e-5f * a;
			const cv::Vec3f na = p_cpu.normals.at<cv::Vec3f>(v, u), nb = p_gpu.normals.at<cv::Vec3f>(v, u);
			if (p_normals) {
				close = close && cv::norm(na - nb) <= 1e-4;
			} else {
				close = close && std::isnan(na[0]) && std::isnan(nb[0]);
			}
			const cv::Vec3b ca = p_cpu.colors.at<cv::Vec3b>(v, u), cb = p_gpu.colors.at<cv::Vec3b>(v, u);
			for (int k = 0; k < 3; k++) {
				close = close && std::abs(int(ca[k]) - int(cb[k])) <= 1;
			}
			out.other += close ? 0 : 1;
		}
	}
	return out;
}

// p_min_hits: the share of pixels that must hit (the test means something only where most rays meet the model).
void check_close(const MapDifference &p_difference, bool p_cpu_device, double p_min_hits = 0.5) {
	MESSAGE(p_difference.pixels, " pixels, ", p_difference.hits, " hits; ", p_difference.bits_differ, " differ in any bit, ", p_difference.other,
			" beyond float rounding; samples CPU ", p_difference.steps_cpu, ", device ", p_difference.steps_gpu);
	CHECK(p_difference.hits > p_min_hits * p_difference.pixels);
	if (p_cpu_device) {
		CHECK(p_difference.bits_differ == 0); // lavapipe: correctly rounded division and square root, no fusing
		CHECK(p_difference.steps_gpu == p_difference.steps_cpu);
	}
	CHECK(p_difference.other <= p_difference.pixels / 500);
}

} // namespace

TEST_CASE("GPU TSDF: raycasts on a Vulkan device give the CPU's points, normals, colours and depths") {
	const std::shared_ptr<ComputeDevice> device = gpu_test_device();
	TsdfVolume cpu, gpu;
	REQUIRE(gpu.set_compute(device) == "");
	REQUIRE(gpu.raycasts_on_gpu());
	for (int i = 0; i < 10; i++) {
		gpu_test_fusion::fuse(&cpu, i);
		gpu_test_fusion::fuse(&gpu, i);
	}
	const PinholeIntrinsics camera = pinhole_intrinsics(half_camera());
	for (const double t : { 0.6, 1.5 }) {
		CAPTURE(t);
		const Pose pose = living_room().trajectory.world_from_rgb(t);
		ModelMaps a, b;
		RaycastStats sa, sb;
		{ // the whole depth range, with normals
			cpu.raycast(camera, pose, &a, &sa);
			gpu.raycast(camera, pose, &b, &sb);
			MapDifference d = compare_maps(a, b, true);
			d.steps_cpu = sa.steps, d.steps_gpu = sb.steps;
			check_close(d, device->is_cpu());
			CHECK(sb.hit_pixels == d.hits);
		}
		{ // a dense face's: a near range, no normals
			cpu.raycast(camera, pose, 0.05f, 2.0f, &a, &sa, false);
			gpu.raycast(camera, pose, 0.05f, 2.0f, &b, &sb, false);
			MapDifference d = compare_maps(a, b, false);
			d.steps_cpu = sa.steps, d.steps_gpu = sb.steps;
			check_close(d, device->is_cpu(), 0.2); // within 2 m: the table and the near walls
		}
		{ // the tracking reference: a quarter size, searched around the frame's readings
			const PinholeIntrinsics quarter = camera.level(1);
			const Frame shot = render_living_room(pose, t, true, 99);
			cv::Mat search(quarter.height, quarter.width, CV_32FC2);
			for (int v = 0; v < quarter.height; v++) {
				for (int u = 0; u < quarter.width; u++) {
					const float d = shot.depth_m.at<float>(2 * v, 2 * u);
					search.at<cv::Vec2f>(v, u) = d > 0.0f ? cv::Vec2f(d - 0.1f, d + 0.1f) : cv::Vec2f(NAN, NAN);
				}
			}
			cpu.raycast(quarter, pose, search, &a, &sa);
			gpu.raycast(quarter, pose, search, &b, &sb);
			MapDifference d = compare_maps(a, b, true);
			d.steps_cpu = sa.steps, d.steps_gpu = sb.steps;
			check_close(d, device->is_cpu());
		}
	}
	CHECK(gpu.compute_problem() == "");
	CHECK(gpu.raycasts_on_gpu());
}
