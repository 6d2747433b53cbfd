// Completing never-observed texels of the coarse texture (paper §4.5): Telea inpainting per
// surface group, floor fill from the walls, observed texels untouched, background worker.

#include <io/opencv.h>

#include "coarse/coarse_texture.h"
#include "coarse/inpainting.h"
#include "room/reference_rooms.h"
#include "room/room_mesh.h"

#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <random>

using namespace roomprobe;

namespace {

RoomMesh test_mesh(double p_texel_size = 0.05) {
	RoomMeshOptions options;
	options.texel_size_m = p_texel_size;
	RoomMeshResult result = build_room_mesh(living_room(), options);
	REQUIRE(result.ok);
	return result.mesh;
}

// An empty texture made here rather than with make_coarse_texture(), so that these tests only
// depend on the plain CoarseTexture struct.
CoarseTexture empty_texture(const RoomMesh &p_mesh) {
	CoarseTexture texture;
	texture.color = cv::Mat(p_mesh.atlas_height, p_mesh.atlas_width, CV_32FC3, cv::Scalar::all(0.0));
	texture.observed = cv::Mat(p_mesh.atlas_height, p_mesh.atlas_width, CV_8UC1, cv::Scalar(0));
	texture.quality = cv::Mat(p_mesh.atlas_height, p_mesh.atlas_width, CV_32FC1, cv::Scalar(0.0));
	texture.updated = cv::Mat(p_mesh.atlas_height, p_mesh.atlas_width, CV_8UC1, cv::Scalar(0));
	return texture;
}

cv::Rect rect_of(const Chart &p_chart) {
	return cv::Rect(p_chart.x, p_chart.y, p_chart.w, p_chart.h);
}

// Marks the whole chart rect observed with one colour.
void observe_chart(CoarseTexture *r_texture, const Chart &p_chart, const cv::Vec3f &p_color) {
	(*r_texture).color(rect_of(p_chart)).setTo(cv::Scalar(p_color[0], p_color[1], p_color[2]));
	(*r_texture).observed(rect_of(p_chart)).setTo(255);
}

const Chart &chart_of_kind(const RoomMesh &p_mesh, SurfaceKind p_kind) {
	for (const Chart &chart : p_mesh.charts) {
		if (chart.kind == p_kind) {
			return chart;
		}
	}
	FAIL("no chart of that kind");
	return p_mesh.charts.front();
}

} // namespace

TEST_CASE("inpainting: a hole in a smooth gradient is filled close to the gradient") {
	const RoomMesh mesh = test_mesh();
	CoarseTexture texture = empty_texture(mesh);
	// Every chart fully observed with a linear gradient in its local texel coordinates.
	const float a = 0.2f, bx = 0.004f, by = 0.006f;
	for (const Chart &chart : mesh.charts) {
		for (int y = 0; y < chart.h; y++) {
			for (int x = 0; x < chart.w; x++) {
				texture.color.at<cv::Vec3f>(chart.y + y, chart.x + x) = cv::Vec3f(a + bx * x + by * y, 0.5f - bx * x, 0.3f + by * y);
			}
		}
		texture.observed(rect_of(chart)).setTo(255);
	}
	// A 12 x 12 hole in the middle of wall 0.
	const Chart &wall = mesh.charts[0];
	REQUIRE(wall.kind == SurfaceKind::Wall);
	const int hole = 12;
	const int hx = wall.w / 2 - hole / 2, hy = wall.h / 2 - hole / 2;
	texture.observed(cv::Rect(wall.x + hx, wall.y + hy, hole, hole)).setTo(0);
	texture.color(cv::Rect(wall.x + hx, wall.y + hy, hole, hole)).setTo(cv::Scalar::all(0.0));

	TextureInpainter inpainter(mesh);
	InpaintReport report;
	const cv::Mat completed = inpainter.inpaint(texture, &report);
	REQUIRE(completed.size() == texture.color.size());
	CHECK(report.walls == GroupFill::Inpainted);
	CHECK(report.floor == GroupFill::NothingMissing);
	CHECK(report.ceiling == GroupFill::NothingMissing);
	CHECK(report.texels_filled == hole * hole);

	// Variation of the gradient over the hole (largest channel sum of slopes times the hole's
	// extent): any weighted average of the hole's surroundings errs by less than about that much.
	// Telea's first-order extrapolation does much better on average; its worst texels (where the
	// fronts from opposite sides meet) measured 0.27 x the variation, mean 0.07 x.
	const double variation = (bx + by) * (hole - 1);
	double max_error = 0.0, sum_error = 0.0;
	for (int y = hy; y < hy + hole; y++) {
		for (int x = hx; x < hx + hole; x++) {
			const cv::Vec3f got = completed.at<cv::Vec3f>(wall.y + y, wall.x + x);
			const cv::Vec3f want(a + bx * x + by * y, 0.5f - bx * x, 0.3f + by * y);
			for (int c = 0; c < 3; c++) {
				const double error = std::abs(got[c] - want[c]);
				max_error = std::max(max_error, error);
				sum_error += error;
			}
		}
	}
	const double mean_error = sum_error / (3.0 * hole * hole);
	INFO("variation over the hole " << variation << ", max error " << max_error << ", mean error " << mean_error);
	CHECK(max_error < 0.4 * variation);
	CHECK(mean_error < 0.1 * variation);
}

TEST_CASE("inpainting: no bleeding between surface groups") {
	const RoomMesh mesh = test_mesh();
	CoarseTexture texture = empty_texture(mesh);
	const Chart &ceiling = chart_of_kind(mesh, SurfaceKind::Ceiling);
	const Chart &floor = chart_of_kind(mesh, SurfaceKind::Floor);
	// Walls blue, observed except their lower half; ceiling red, observed only in its left third;
	// floor green, observed only in its top-left quarter.
	for (const Chart &chart : mesh.charts) {
		if (chart.kind == SurfaceKind::Wall) {
			observe_chart(&texture, chart, cv::Vec3f(0.05f, 0.1f, 0.9f));
			texture.observed(cv::Rect(chart.x, chart.y + chart.h / 2, chart.w, chart.h - chart.h / 2)).setTo(0);
		}
	}
	observe_chart(&texture, ceiling, cv::Vec3f(0.9f, 0.05f, 0.02f));
	texture.observed(cv::Rect(ceiling.x + ceiling.w / 3, ceiling.y, ceiling.w - ceiling.w / 3, ceiling.h)).setTo(0);
	observe_chart(&texture, floor, cv::Vec3f(0.1f, 0.8f, 0.1f));
	texture.observed(cv::Rect(floor.x + floor.w / 2, floor.y, floor.w - floor.w / 2, floor.h)).setTo(0);
	texture.observed(cv::Rect(floor.x, floor.y + floor.h / 2, floor.w / 2, floor.h - floor.h / 2)).setTo(0);

	TextureInpainter inpainter(mesh);
	InpaintReport report;
	const cv::Mat completed = inpainter.inpaint(texture, &report);
	CHECK(report.walls == GroupFill::Inpainted);
	CHECK(report.floor == GroupFill::Inpainted);
	CHECK(report.ceiling == GroupFill::Inpainted);

	int checked = 0;
	for (int y = 0; y < mesh.atlas_height; y++) {
		for (int x = 0; x < mesh.atlas_width; x++) {
			const int index = find_chart_at_texel(mesh, x, y);
			if (index < 0 || texture.observed.at<uint8_t>(y, x) != 0) {
				continue;
			}
			const cv::Vec3f got = completed.at<cv::Vec3f>(y, x);
			const Chart &chart = mesh.charts[static_cast<size_t>(index)];
			cv::Vec3f want;
			switch (chart.kind) {
				case SurfaceKind::Wall:
					want = cv::Vec3f(0.05f, 0.1f, 0.9f);
					break;
				case SurfaceKind::Floor:
					want = cv::Vec3f(0.1f, 0.8f, 0.1f);
					break;
				case SurfaceKind::Ceiling:
					want = cv::Vec3f(0.9f, 0.05f, 0.02f);
					break;
			}
			// Constant colour per group: anything but that colour came from another group.
			for (int c = 0; c < 3; c++) {
				if (std::abs(got[c] - want[c]) > 1e-4f) {
					FAIL_CHECK("texel (" << x << ", " << y << ") of " << surface_kind_name(chart.kind) << " is " << got[0] << ", " << got[1] << ", " << got[2]);
					return;
				}
			}
			checked++;
		}
	}
	CHECK(checked == report.texels_filled);
}

TEST_CASE("inpainting: an unobserved floor takes the walls' lower-band colour, the ceiling the upper band") {
	const RoomMesh mesh = test_mesh();
	CoarseTexture texture = empty_texture(mesh);
	const cv::Vec3f upper(0.8f, 0.75f, 0.7f), lower(0.15f, 0.4f, 0.25f);
	for (const Chart &chart : mesh.charts) {
		if (chart.kind != SurfaceKind::Wall) {
			continue;
		}
		observe_chart(&texture, chart, upper);
		// Bottom 30 % of the wall (more than the default 20 % band) in the skirting colour.
		const int skirting = static_cast<int>(std::ceil(0.3 * chart.h));
		texture.color(cv::Rect(chart.x, chart.y + chart.h - skirting, chart.w, skirting)).setTo(cv::Scalar(lower[0], lower[1], lower[2]));
		// The top rows observed, a middle band not: the walls still need inpainting.
		texture.observed(cv::Rect(chart.x, chart.y + chart.h / 3, chart.w, chart.h / 4)).setTo(0);
	}
	TextureInpainter inpainter(mesh);
	InpaintReport report;
	const cv::Mat completed = inpainter.inpaint(texture, &report);
	CHECK(report.walls == GroupFill::Inpainted);
	CHECK(report.floor == GroupFill::FromWalls);
	CHECK(report.ceiling == GroupFill::FromWalls);
	const Chart &floor = chart_of_kind(mesh, SurfaceKind::Floor);
	const Chart &ceiling = chart_of_kind(mesh, SurfaceKind::Ceiling);
	for (int c = 0; c < 3; c++) {
		CHECK(completed.at<cv::Vec3f>(floor.y + floor.h / 2, floor.x + floor.w / 2)[c] == doctest::Approx(lower[c]).epsilon(1e-4));
		CHECK(completed.at<cv::Vec3f>(floor.y, floor.x)[c] == doctest::Approx(lower[c]).epsilon(1e-4));
		CHECK(completed.at<cv::Vec3f>(ceiling.y + ceiling.h / 2, ceiling.x + ceiling.w / 2)[c] == doctest::Approx(upper[c]).epsilon(1e-4));
	}

	SUBCASE("switched off: fallback grey") {
		InpaintingOptions options;
		options.fill_floor_from_walls = false;
		TextureInpainter plain(mesh, options);
		const cv::Mat grey = plain.inpaint(texture, &report);
		CHECK(report.floor == GroupFill::Fallback);
		CHECK(grey.at<cv::Vec3f>(floor.y + 1, floor.x + 1)[1] == doctest::Approx(0.5f));
	}
	SUBCASE("nothing observed anywhere: fallback grey everywhere") {
		const CoarseTexture blank = empty_texture(mesh);
		const cv::Mat grey = inpainter.inpaint(blank, &report);
		CHECK(report.walls == GroupFill::Fallback);
		CHECK(report.floor == GroupFill::Fallback);
		CHECK(report.ceiling == GroupFill::Fallback);
		CHECK(grey.at<cv::Vec3f>(mesh.charts[0].y + 1, mesh.charts[0].x + 1)[0] == doctest::Approx(0.5f));
	}
}

TEST_CASE("inpainting: observed texels are bit-identical, the input is not modified") {
	const RoomMesh mesh = test_mesh();
	CoarseTexture texture = empty_texture(mesh);
	std::mt19937 rng(7);
	std::uniform_real_distribution<float> value(0.0f, 3.0f); // HDR values too.
	std::bernoulli_distribution seen(0.6);
	for (int y = 0; y < mesh.atlas_height; y++) {
		for (int x = 0; x < mesh.atlas_width; x++) {
			if (find_chart_at_texel(mesh, x, y) >= 0 && seen(rng)) {
				texture.color.at<cv::Vec3f>(y, x) = cv::Vec3f(value(rng), value(rng), value(rng));
				texture.observed.at<uint8_t>(y, x) = 255;
			}
		}
	}
	// A never-observed texel may hold anything (e.g. stale data); it must not leak into the output.
	const cv::Mat before = texture.color.clone();
	const cv::Mat observed_before = texture.observed.clone();
	TextureInpainter inpainter(mesh);
	InpaintReport report;
	const cv::Mat completed = inpainter.inpaint(texture, &report);
	REQUIRE(completed.type() == CV_32FC3);
	CHECK(report.texels_filled > 0);
	CHECK(cv::norm(texture.observed, observed_before, cv::NORM_INF) == 0.0);
	CHECK(std::memcmp(texture.color.data, before.data, before.total() * before.elemSize()) == 0);
	int differing = 0;
	int filled = 0;
	for (int y = 0; y < mesh.atlas_height; y++) {
		for (int x = 0; x < mesh.atlas_width; x++) {
			const cv::Vec3f &got = completed.at<cv::Vec3f>(y, x);
			const cv::Vec3f &was = before.at<cv::Vec3f>(y, x);
			if (texture.observed.at<uint8_t>(y, x) != 0 || find_chart_at_texel(mesh, x, y) < 0) {
				differing += std::memcmp(&got, &was, sizeof(cv::Vec3f)) != 0;
			} else {
				filled++;
			}
		}
	}
	CHECK(differing == 0);
	CHECK(filled == report.texels_filled);
}

TEST_CASE("inpainting: the worker returns the newest request's result and joins cleanly") {
	const RoomMesh mesh = test_mesh();
	std::vector<CoarseTexture> textures;
	for (int i = 0; i < 4; i++) {
		CoarseTexture texture = empty_texture(mesh);
		for (const Chart &chart : mesh.charts) {
			observe_chart(&texture, chart, cv::Vec3f(0.1f * (i + 1), 0.2f, 0.3f));
			texture.observed(cv::Rect(chart.x, chart.y, chart.w / 2, chart.h)).setTo(0);
		}
		textures.push_back(texture);
	}
	{
		TextureInpainter inpainter(mesh);
		cv::Mat result;
		CHECK_FALSE(inpainter.try_take_result(&result));
		uint64_t last = 0;
		for (const CoarseTexture &texture : textures) {
			last = inpainter.request(texture);
		}
		CHECK(last == textures.size());
		inpainter.wait_idle();
		uint64_t id = 0;
		InpaintReport report;
		REQUIRE(inpainter.try_take_result(&result, &id, &report));
		CHECK(id == last);
		CHECK(report.walls == GroupFill::Inpainted);
		const cv::Mat expected = inpainter.inpaint(textures.back());
		REQUIRE(result.size() == expected.size());
		CHECK(cv::norm(result, expected, cv::NORM_INF) == 0.0);
		CHECK_FALSE(inpainter.try_take_result(&result)); // Taken already.

		// The snapshot is a copy: changing the texture after request() does not change the result.
		CoarseTexture changing = textures[0];
		changing.color = textures[0].color.clone(); // cv::Mat copies share data.
		inpainter.request(changing);
		changing.color.setTo(cv::Scalar::all(9.0));
		inpainter.wait_idle();
		REQUIRE(inpainter.try_take_result(&result, &id));
		CHECK(id == last + 1);
		CHECK(cv::norm(result, inpainter.inpaint(textures[0]), cv::NORM_INF) == 0.0);
	}
	{
		// Destroyed with requests pending and running: joins without hanging.
		TextureInpainter inpainter(mesh);
		inpainter.request(textures[0]);
		inpainter.request(textures[1]);
	}
	CHECK(true);
}
