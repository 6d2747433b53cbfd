// ICP's point-to-plane rows eight pixels at a time (extension/core/slam/icp_accumulate_simd.h)
// against the scalar kernel (icp_correspondence) on the same pixels: the same pairs, and sums
// that agree to float rounding.

#include <io/opencv.h>

#include "camera/pinhole_camera.h"
#include "slam/depth_pyramid.h"
#include "slam/icp_accumulate_simd.h"
#include "slam/icp_kernels.h"
#include "slam/icp_tracker.h"
#include "synth_test_frames.h"

#include <doctest/doctest.h>

#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <limits>

using namespace roomprobe;
using namespace synth_frames;

TEST_CASE("ICP rows eight pixels at a time (AVX2): the scalar kernel's pairs, and its sums to float rounding") {
	if (!icp_simd_available()) {
		MESSAGE("this CPU has no AVX2: only the scalar kernel runs here");
		return;
	}
	const PinholeIntrinsics camera = pinhole_intrinsics(half_camera());
	const Pose reference_pose = living_room().trajectory.world_from_rgb(3.0);
	const Pose current_pose = moved(reference_pose, { 0.3, 1.0, 0.2 }, 2.0, { 0.02, -0.01, 0.03 });
	const Frame reference = render_living_room(reference_pose, 3.0, true, 11);
	const Frame current = render_living_room(current_pose, 3.0, true, 12);
	const ModelMaps model = make_model_maps(reference.depth_m, reference.rgb, camera, reference_pose);
	// Holes in the frame (a band of rows and a column), so that invalid lanes come mixed with valid ones.
	cv::Mat depth = current.depth_m.clone();
	depth.rowRange(100, 110).setTo(std::numeric_limits<float>::quiet_NaN());
	depth.col(37).setTo(std::numeric_limits<float>::quiet_NaN());
	const cv::Mat vertices = compute_vertex_map(smooth_depth(depth, 2, 0.05f), camera);
	const cv::Mat normals = compute_normal_map(vertices, 0.1f);

	IcpModelView view;
	view.points = model.points.ptr<float>();
	view.normals = model.normals.ptr<float>();
	view.stride = model.points.step1();
	view.camera = camera;
	const Pose camera_from_world = inverse(reference_pose);
	view.camera_from_world_rotation = glm::mat3(glm::mat3_cast(camera_from_world.rotation));
	view.camera_from_world_translation = glm::vec3(camera_from_world.translation);
	IcpKernelParams params; // the estimate: the reference's pose, so that some pairs fail the tests
	params.rotation = glm::mat3(glm::mat3_cast(reference_pose.rotation));
	params.translation = glm::vec3(reference_pose.translation);
	params.max_distance_m = 0.05f;
	params.min_normal_cos = std::cos(0.5f);
	params.noise_b_per_m2 = 0.0019f; // far readings weighed down: both branches of the weight
	params.noise_reference_sigma_m = 0.0012f + 0.0019f * 0.01f;

	for (const int stride : { 1, 2 }) {
		CAPTURE(stride);
		const int count = (vertices.cols / stride) / 8 * 8;
		IcpRowTotals simd;
		double reference_sums[IcpRowTotals::SUMS] = {}, magnitude[IcpRowTotals::SUMS] = {};
		int reference_inliers = 0;
		for (int y = 0; y < vertices.rows; y += stride) {
			const cv::Vec3f *v = vertices.ptr<cv::Vec3f>(y);
			const cv::Vec3f *n = normals.ptr<cv::Vec3f>(y);
			icp_accumulate_row_simd(&v[0][0], &n[0][0], count, stride, params, view, &simd);
			for (int k = 0; k < count; k++) {
				const int x = k * stride;
				IcpRow rows[2];
				float squared = 0.0f;
				if (icp_correspondence(glm::vec3(v[x][0], v[x][1], v[x][2]), glm::vec3(n[x][0], n[x][1], n[x][2]), std::nanf(""), params, view, rows,
							&squared) == 0) {
					continue;
				}
				reference_inliers++;
				const float *j = rows[0].jacobian;
				double terms[IcpRowTotals::SUMS];
				int t = 0;
				for (int a = 0; a < 6; a++) {
					for (int b = a; b < 6; b++) {
						terms[t++] = double(j[a] * j[b]);
					}
				}
				for (int a = 0; a < 6; a++) {
					terms[21 + a] = double(j[a] * rows[0].residual);
				}
				terms[27] = double(j[0] * j[0] + j[1] * j[1] + j[2] * j[2]);
				terms[28] = double(j[3] * j[3] + j[4] * j[4] + j[5] * j[5]);
				terms[29] = double(squared);
				for (int s = 0; s < IcpRowTotals::SUMS; s++) {
					reference_sums[s] += terms[s];
					magnitude[s] += std::abs(terms[s]);
				}
			}
		}
		CHECK(reference_inliers > count * vertices.rows / stride / 4); // most pixels pair
		CHECK(reference_inliers < count * vertices.rows / stride); // and some do not
		CHECK(simd.inliers == reference_inliers);
		for (int s = 0; s < IcpRowTotals::SUMS; s++) {
			CAPTURE(s);
			// A lane sums a row's terms in float, 40 of them here (320 columns, stride 1): relative
			// rounding up to about 40 x 6e-8 = 2.4e-6 of the terms' magnitude; 2e-5 allows 8x that.
			CHECK(std::abs(simd.sums[s] - reference_sums[s]) <= 2e-5 * magnitude[s] + 1e-12);
		}
	}
}
