// pipeline/coarse_pipeline.h: the coarse model end to end.

#include <io/opencv.h>

#include "pipeline/coarse_pipeline.h"
#include "synth_test_rig.h"

#include <doctest/doctest.h>

#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <numbers>
#include <vector>

using namespace roomprobe;

namespace {

OmniParams small_fisheye() {
	return scaled_test_fisheye(4); // 256 x 256
}

Floorplan box_room() {
	Floorplan plan;
	plan.points = { Vec2(0.0, 0.0), Vec2(4.0, 0.0), Vec2(4.0, 3.0), Vec2(0.0, 3.0) };
	plan.ceiling_height_m = 2.5;
	return plan;
}

} // namespace

TEST_CASE("pipeline: a flat-coloured convex room is reproduced at the camera") {
	const cv::Vec3f colour(0.3f, 0.5f, 0.7f);
	CoarsePipelineOptions options;
	options.texel_size_m = 0.05;
	options.cubemap_size = 32;
	options.lighting = true;
	CoarsePipeline pipeline(options);
	CHECK_FALSE(pipeline.is_configured());
	const OmniParams fisheye = small_fisheye();
	REQUIRE(pipeline.configure(fisheye, box_room()) == "");
	REQUIRE(pipeline.is_configured());

	// An upward fisheye in the middle of the room seeing a uniformly coloured room.
	FisheyeFrame frame;
	frame.image = cv::Mat(fisheye.height, fisheye.width, CV_32FC3, cv::Scalar(colour[0], colour[1], colour[2]));
	frame.hdr = true;
	Pose pose;
	pose.rotation = glm::angleAxis(-std::numbers::pi / 2.0, glm::dvec3(1.0, 0.0, 0.0)); // camera +z -> world +y
	pose.translation = glm::dvec3(2.0, 1.4, 1.5);
	REQUIRE(glm::length((pose.rotation * glm::dvec3(0.0, 0.0, 1.0)) - glm::dvec3(0.0, 1.0, 0.0)) < 1e-9);

	const CoarseFrameStats first = pipeline.add_fisheye_frame(frame, pose);
	CHECK(first.occlusion_skipped); // convex
	CHECK(first.update.texels_updated > 1000);
	CHECK_FALSE(first.lighting.valid); // nothing to compare against yet
	CHECK(cv::countNonZero(pipeline.texture().observed) == int(first.update.texels_updated));
	CHECK(cv::countNonZero(pipeline.texture().observed) < int(pipeline.texture().observed.total())); // the floor is not seen

	// A second identical frame: the lighting change is (close to) the identity.
	const CoarseFrameStats second = pipeline.add_fisheye_frame(frame, pose);
	CHECK(second.lighting.valid);
	for (int c = 0; c < 3; c++) {
		CHECK(second.lighting.gain[c] == doctest::Approx(1.0).epsilon(1e-3));
	}
	CHECK(pipeline.frame_count() == 2);

	const Cubemap map = pipeline.render_cubemap(pose.translation);
	REQUIRE(is_valid_cubemap(map));
	CHECK(map.size == 32);
	double worst = 0.0;
	for (int f = 0; f < 6; f++) {
		for (int y = 0; y < map.size; y++) {
			for (int x = 0; x < map.size; x++) {
				const cv::Vec3f v = map.faces[f].at<cv::Vec3f>(y, x);
				for (int c = 0; c < 3; c++) {
					worst = std::max(worst, double(std::abs(v[c] - colour[c])));
				}
			}
		}
	}
	CHECK(worst < 0.01); // inpainting completes the unseen floor from the walls' colour
	const ShCoefficients sh = pipeline.sh(pose.translation);
	// A constant radiance L projects onto y_0^0 only: c_0 = L * 4 pi / (2 sqrt(pi)) = L * 2 sqrt(pi).
	CHECK(sh[0].y == doctest::Approx(0.5 * 2.0 * std::sqrt(std::numbers::pi)).epsilon(0.01));
	CHECK(pipeline.last_timings().frame_ms > 0.0);
	CHECK(pipeline.total_timings().update_ms > 0.0);
}

TEST_CASE("pipeline: a lighting change is carried to texels the frame does not update") {
	CoarsePipelineOptions options;
	options.texel_size_m = 0.05;
	options.cubemap_size = 16;
	options.inpaint = false;
	options.lighting = true;
	options.lighting_model = LightingModel::GAIN_ROBUST;
	CoarsePipeline pipeline(options);
	const OmniParams fisheye = small_fisheye();
	REQUIRE(pipeline.configure(fisheye, box_room()) == "");
	Pose up;
	up.rotation = glm::angleAxis(-std::numbers::pi / 2.0, glm::dvec3(1.0, 0.0, 0.0));
	up.translation = glm::dvec3(2.0, 1.4, 1.5);
	FisheyeFrame dim;
	dim.image = cv::Mat(fisheye.height, fisheye.width, CV_32FC3, cv::Scalar(0.2, 0.2, 0.2));
	pipeline.add_fisheye_frame(dim, up);
	// Tilted 60 degrees towards -z: sees part of the previous view, misses the rest; the room is
	// twice as bright now.
	Pose tilted = up;
	tilted.rotation = glm::angleAxis(std::numbers::pi / 3.0, glm::dvec3(1.0, 0.0, 0.0)) * up.rotation;
	FisheyeFrame bright;
	bright.image = cv::Mat(fisheye.height, fisheye.width, CV_32FC3, cv::Scalar(0.4, 0.4, 0.4));
	const CoarseFrameStats stats = pipeline.add_fisheye_frame(bright, tilted);
	REQUIRE(stats.lighting.valid);
	CHECK(stats.lighting.gain[0] == doctest::Approx(2.0).epsilon(0.01));
	// Every observed texel is now 0.4: updated ones directly, the others by the gain.
	const CoarseTexture &texture = pipeline.texture();
	int observed = 0, not_updated = 0;
	double worst = 0.0;
	for (int y = 0; y < texture.color.rows; y++) {
		for (int x = 0; x < texture.color.cols; x++) {
			if (!texture.observed.at<uint8_t>(y, x)) {
				continue;
			}
			observed++;
			not_updated += texture.updated.at<uint8_t>(y, x) ? 0 : 1;
			worst = std::max(worst, double(std::abs(texture.color.at<cv::Vec3f>(y, x)[1] - 0.4f)));
		}
	}
	CHECK(observed > 0);
	CHECK(not_updated > 100);
	CHECK(worst < 0.01);
}

TEST_CASE("pipeline: asynchronous inpainting composes the worker's fill under the texels observed now") {
	CoarsePipelineOptions options;
	options.texel_size_m = 0.05;
	options.cubemap_size = 16;
	options.lighting = false;
	options.inpaint_async = true;
	CoarsePipeline sync_pipeline([&] {
		CoarsePipelineOptions o = options;
		o.inpaint_async = false;
		return o;
	}());
	CoarsePipeline pipeline(options);
	const OmniParams fisheye = small_fisheye();
	REQUIRE(pipeline.configure(fisheye, box_room()) == "");
	REQUIRE(sync_pipeline.configure(fisheye, box_room()) == "");
	Pose up;
	up.rotation = glm::angleAxis(-std::numbers::pi / 2.0, glm::dvec3(1.0, 0.0, 0.0));
	up.translation = glm::dvec3(2.0, 1.4, 1.5);
	FisheyeFrame frame;
	frame.image = cv::Mat(fisheye.height, fisheye.width, CV_32FC3, cv::Scalar(0.25, 0.5, 0.75));
	pipeline.add_fisheye_frame(frame, up);
	sync_pipeline.add_fisheye_frame(frame, up);

	// Right after the frame the observed texels are there whether or not the worker has finished.
	const cv::Mat observed = pipeline.texture().observed;
	cv::Mat diff;
	cv::absdiff(pipeline.completed_color(), pipeline.texture().color, diff);
	double worst_observed = 0.0;
	cv::Mat mask3;
	cv::merge(std::vector<cv::Mat>{ observed, observed, observed }, mask3); // a channel mask per value
	cv::minMaxLoc(diff.reshape(1), nullptr, &worst_observed, nullptr, nullptr, mask3.reshape(1));
	CHECK(worst_observed == 0.0);

	// Once the worker is done, the completed texture is the synchronous one.
	pipeline.finish_inpainting();
	cv::absdiff(pipeline.completed_color(), sync_pipeline.completed_color(), diff);
	double worst = 0.0;
	cv::minMaxLoc(diff.reshape(1), nullptr, &worst);
	CHECK(worst < 1e-6);
	CHECK(cv::countNonZero(observed) < int(observed.total())); // there was something to fill
}
