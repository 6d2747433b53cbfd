// The coarse cubemap's gather on a Vulkan device (envmap/coarse_render_gpu.h) against the CPU's
// (envmap/coarse_render.h), on gpu_test_device() (lavapipe in CI). The kernel adds the taps in the
// CPU's order without fused multiply-adds, so the faces must be equal to the bit.

#include "envmap/coarse_render.h"
#include "gpu_test_device.h"
#include "room/room_mesh.h"

#include <doctest/doctest.h>

#include <opencv2/core.hpp>

using namespace roomprobe;

namespace {

// An L-shaped room, 2.5 m high: walls, floor and ceiling charts of several sizes.
RoomMesh l_room_mesh() {
	Floorplan floorplan;
	floorplan.points = { { 0.0, 0.0 }, { 4.0, 0.0 }, { 4.0, 1.5 }, { 2.0, 1.5 }, { 2.0, 3.0 }, { 0.0, 3.0 } };
	floorplan.ceiling_height_m = 2.5;
	const RoomMeshResult result = build_room_mesh(floorplan);
	REQUIRE_MESSAGE(result.ok, result.error);
	return result.mesh;
}

// An atlas of p_type (CV_32FC1 or CV_32FC3) with values in [0, p_max): noise, so that every tap's
// weight shows.
cv::Mat noise_atlas(const RoomMesh &p_mesh, int p_type, float p_max, uint64_t p_seed) {
	cv::Mat atlas(p_mesh.atlas_height, p_mesh.atlas_width, p_type);
	cv::RNG rng(p_seed);
	rng.fill(atlas, cv::RNG::UNIFORM, 0.0, double(p_max));
	return atlas;
}

// The largest difference between the faces, and whether every texel is equal to the bit.
double faces_difference(const std::array<cv::Mat, 6> &p_a, const std::array<cv::Mat, 6> &p_b) {
	double worst = 0.0;
	for (size_t f = 0; f < 6; f++) {
		REQUIRE(p_a[f].size() == p_b[f].size());
		REQUIRE(p_a[f].type() == p_b[f].type());
		worst = std::max(worst, cv::norm(p_a[f], p_b[f], cv::NORM_INF));
	}
	return worst;
}

} // namespace

TEST_CASE("GPU coarse: the coarse render's gather on a Vulkan device gives the CPU's faces to the bit, colour and mask") {
	const RoomMesh mesh = l_room_mesh();
	const CoarseCubemapRenderer cpu(mesh);
	CoarseCubemapRenderer gpu(mesh);
	gpu.set_compute(gpu_test_device());
	REQUIRE_MESSAGE(gpu.gathers_on_gpu(), gpu.compute_problem());
	const cv::Mat colour = noise_atlas(mesh, CV_32FC3, 8.0f, 1);
	const cv::Mat mask = noise_atlas(mesh, CV_32FC1, 1.0f, 2);
	const glm::dquat turned = glm::angleAxis(0.3, glm::dvec3(0.0, 1.0, 0.0));
	for (const int size : { 16, 48 }) {
		for (const glm::dvec3 &position : { glm::dvec3(1.3, 1.1, 0.9), glm::dvec3(3.1, 0.4, 0.7) }) {
			CAPTURE(size);
			CAPTURE(position.x);
			const Cubemap a = cpu.render(colour, position, size, turned, true);
			const Cubemap b = gpu.render(colour, position, size, turned, true);
			REQUIRE(is_valid_cubemap(b));
			CHECK(faces_difference(a.faces, b.faces) == 0.0);
			CHECK(faces_difference(a.distance_m, b.distance_m) == 0.0);
			CHECK(faces_difference(cpu.render_channel(mask, position, size, turned, true), gpu.render_channel(mask, position, size, turned, true)) == 0.0);
		}
	}
	CHECK(gpu.compute_problem().empty());
}

TEST_CASE("GPU coarse: a published atlas stays on the device, another is uploaded, and one written in place shows when not published") {
	const RoomMesh mesh = l_room_mesh();
	CoarseCubemapRenderer gpu(mesh);
	gpu.set_compute(gpu_test_device());
	REQUIRE_MESSAGE(gpu.gathers_on_gpu(), gpu.compute_problem());
	const CoarseCubemapRenderer cpu(mesh);
	const glm::dvec3 position(1.3, 1.1, 0.9);
	const int size = 24;
	const cv::Mat first = noise_atlas(mesh, CV_32FC3, 4.0f, 3);
	const cv::Mat second = noise_atlas(mesh, CV_32FC3, 4.0f, 4);
	CHECK(faces_difference(gpu.render(first, position, size, glm::dquat(1, 0, 0, 0), true).faces, cpu.render(first, position, size).faces) == 0.0);
	// Another published atlas is another buffer: uploaded, whatever the first left on the device.
	CHECK(faces_difference(gpu.render(second, position, size, glm::dquat(1, 0, 0, 0), true).faces, cpu.render(second, position, size).faces) == 0.0);
	// An atlas that is not published is uploaded on every render: writing into it shows at once.
	cv::Mat live = first.clone();
	CHECK(faces_difference(gpu.render(live, position, size).faces, cpu.render(first, position, size).faces) == 0.0);
	live *= 2.0;
	CHECK(faces_difference(gpu.render(live, position, size).faces, cpu.render(live, position, size).faces) == 0.0);
	// A view with gaps (not continuous) is gathered from its copy.
	cv::Mat wide(mesh.atlas_height, mesh.atlas_width + 3, CV_32FC3, cv::Scalar::all(0.0));
	second.copyTo(wide(cv::Rect(0, 0, mesh.atlas_width, mesh.atlas_height)));
	const cv::Mat view = wide(cv::Rect(0, 0, mesh.atlas_width, mesh.atlas_height));
	REQUIRE_FALSE(view.isContinuous());
	CHECK(faces_difference(gpu.render(view, position, size, glm::dquat(1, 0, 0, 0), true).faces, cpu.render(second, position, size).faces) == 0.0);
}

TEST_CASE("GPU coarse: a device lost mid-way puts the gather back on the CPU, with the reason, and the faces stay right") {
	const RoomMesh mesh = l_room_mesh();
	const std::shared_ptr<ComputeDevice> device = gpu_test_device();
	CoarseCubemapRenderer gpu(mesh);
	gpu.set_compute(device);
	REQUIRE(gpu.gathers_on_gpu());
	const CoarseCubemapRenderer cpu(mesh);
	const cv::Mat colour = noise_atlas(mesh, CV_32FC3, 4.0f, 5);
	const glm::dvec3 position(1.0, 1.2, 2.0);
	CHECK(faces_difference(gpu.render(colour, position, 20).faces, cpu.render(colour, position, 20).faces) == 0.0);
	CHECK(gpu.compute_problem().empty());
	device->simulate_loss();
	CHECK(faces_difference(gpu.render(colour, position, 20).faces, cpu.render(colour, position, 20).faces) == 0.0);
	CAPTURE(gpu.compute_problem());
	CHECK(gpu.compute_problem().find("the coarse render on the CPU") != std::string::npos);
	// Back to the CPU for good: no device, no problem.
	gpu.set_compute(nullptr);
	CHECK_FALSE(gpu.gathers_on_gpu());
	CHECK(gpu.compute_problem().empty());
}
