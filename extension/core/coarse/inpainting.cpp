#include "inpainting.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/photo.hpp>
#pragma GCC diagnostic pop

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

namespace roomprobe {

const char *group_fill_name(GroupFill p_fill) {
	switch (p_fill) {
		case GroupFill::NothingMissing:
			return "nothing missing";
		case GroupFill::Inpainted:
			return "inpainted";
		case GroupFill::FromWalls:
			return "from walls";
		case GroupFill::Fallback:
			return "fallback colour";
	}
	return "?";
}

TextureInpainter::TextureInpainter(const RoomMesh &p_mesh, const InpaintingOptions &p_options) :
		options(p_options), atlas_width(p_mesh.atlas_width), atlas_height(p_mesh.atlas_height) {
	if (!(options.inpaint_radius_texels > 0.0)) {
		options.inpaint_radius_texels = 3.0;
	}
	if (!(options.wall_band_fraction > 0.0) || options.wall_band_fraction > 1.0) {
		options.wall_band_fraction = 0.2;
	}
	std::vector<std::pair<int, ChartRect>> wall_list;
	for (const Chart &chart : p_mesh.charts) {
		ChartRect rect;
		rect.x = chart.x;
		rect.y = chart.y;
		rect.w = chart.w;
		rect.h = chart.h;
		rect.used_w = chart.used_w_texels;
		rect.used_h = chart.used_h_texels;
		if (rect.w <= 0 || rect.h <= 0 || rect.x < 0 || rect.y < 0 || rect.x + rect.w > atlas_width || rect.y + rect.h > atlas_height) {
			continue; // Not a usable rect; the mesh builder never makes one.
		}
		switch (chart.kind) {
			case SurfaceKind::Wall:
				wall_list.emplace_back(chart.wall_index, rect);
				break;
			case SurfaceKind::Floor:
				floor_rect = rect;
				has_floor = true;
				break;
			case SurfaceKind::Ceiling:
				ceiling_rect = rect;
				has_ceiling = true;
				break;
		}
	}
	std::stable_sort(wall_list.begin(), wall_list.end(), [](const auto &p_a, const auto &p_b) { return p_a.first < p_b.first; });
	for (const auto &[index, rect] : wall_list) {
		walls.push_back(rect);
		wall_strip_x.push_back(strip_width);
		strip_width += rect.w;
		strip_height = std::max(strip_height, rect.h);
	}
	// Wrap-around context on each side of the strip: enough for Telea's radius and for colour to
	// reach a little way round the corner between the last and the first wall.
	strip_pad = std::min(strip_width, std::max(16, static_cast<int>(std::ceil(4.0 * options.inpaint_radius_texels))));

	worker = std::thread([this]() { worker_loop(); });
}

TextureInpainter::~TextureInpainter() {
	{
		std::lock_guard<std::mutex> lock(mutex);
		stopping = true;
	}
	wake.notify_all();
	idle.notify_all();
	if (worker.joinable()) {
		worker.join();
	}
}

bool TextureInpainter::telea(const cv::Mat &p_color, const cv::Mat &p_known, cv::Mat *r_out) const {
	if (cv::countNonZero(p_known) == 0) {
		return false;
	}
	cv::Mat mask;
	cv::compare(p_known, 0, mask, cv::CMP_EQ);
	cv::Mat channels[3];
	cv::split(p_color, channels);
	for (cv::Mat &channel : channels) {
		// 16-bit fixed point scaled to this channel's largest known value (see the header).
		double largest = 0.0;
		cv::minMaxLoc(channel, nullptr, &largest, nullptr, nullptr, p_known);
		const double scale = largest > 1e-12 ? 65535.0 / largest : 1.0;
		cv::Mat fixed;
		channel.convertTo(fixed, CV_16U, scale); // Saturates: negative values become 0.
		cv::Mat filled;
		cv::inpaint(fixed, mask, filled, options.inpaint_radius_texels, cv::INPAINT_TELEA);
		filled.convertTo(channel, CV_32F, 1.0 / scale);
	}
	cv::merge(channels, 3, *r_out);
	return true;
}

void TextureInpainter::fill_walls(const cv::Mat &p_color, const cv::Mat &p_observed, cv::Mat *r_out, InpaintReport *r_report) const {
	if (walls.empty()) {
		r_report->walls = GroupFill::NothingMissing;
		return;
	}
	int observed_count = 0;
	int area = 0;
	for (const ChartRect &rect : walls) {
		observed_count += cv::countNonZero(p_observed(cv::Rect(rect.x, rect.y, rect.w, rect.h)));
		area += rect.w * rect.h;
	}
	if (observed_count == area) {
		r_report->walls = GroupFill::NothingMissing;
		return;
	}
	cv::Mat filled_strip;
	if (observed_count == 0) {
		r_report->walls = GroupFill::Fallback;
	} else {
		const int full_width = strip_width + 2 * strip_pad;
		cv::Mat strip(strip_height, full_width, CV_32FC3, cv::Scalar::all(0.0));
		cv::Mat known(strip_height, full_width, CV_8UC1, cv::Scalar(0));
		for (size_t i = 0; i < walls.size(); i++) {
			const ChartRect &rect = walls[i];
			const cv::Rect src(rect.x, rect.y, rect.w, rect.h);
			const cv::Rect dst(strip_pad + wall_strip_x[i], 0, rect.w, rect.h);
			p_color(src).copyTo(strip(dst));
			p_observed(src).copyTo(known(dst));
		}
		if (strip_pad > 0) {
			// Left pad: the strip's last columns; right pad: its first columns.
			const cv::Rect tail(strip_width, 0, strip_pad, strip_height);
			const cv::Rect head(strip_pad, 0, strip_pad, strip_height);
			strip(tail).copyTo(strip(cv::Rect(0, 0, strip_pad, strip_height)));
			known(tail).copyTo(known(cv::Rect(0, 0, strip_pad, strip_height)));
			strip(head).copyTo(strip(cv::Rect(strip_pad + strip_width, 0, strip_pad, strip_height)));
			known(head).copyTo(known(cv::Rect(strip_pad + strip_width, 0, strip_pad, strip_height)));
		}
		telea(strip, known, &filled_strip);
		r_report->walls = GroupFill::Inpainted;
	}
	for (size_t i = 0; i < walls.size(); i++) {
		const ChartRect &rect = walls[i];
		const cv::Rect src(rect.x, rect.y, rect.w, rect.h);
		cv::Mat missing;
		cv::compare(p_observed(src), 0, missing, cv::CMP_EQ);
		cv::Mat target = (*r_out)(src);
		if (filled_strip.empty()) {
			target.setTo(cv::Scalar(options.fallback_color[0], options.fallback_color[1], options.fallback_color[2]), missing);
		} else {
			filled_strip(cv::Rect(strip_pad + wall_strip_x[i], 0, rect.w, rect.h)).copyTo(target, missing);
		}
	}
	r_report->texels_filled += area - observed_count;
}

cv::Vec3f TextureInpainter::wall_band_mean(const cv::Mat &p_completed, bool p_bottom) const {
	cv::Vec3d sum(0.0, 0.0, 0.0);
	long count = 0;
	for (const ChartRect &rect : walls) {
		// Texel r's centre r + 0.5 lies on the surface while r + 0.5 <= used.
		const int last_row = std::clamp(static_cast<int>(std::ceil(rect.used_h - 0.5)) - 1, 0, rect.h - 1);
		const int last_col = std::clamp(static_cast<int>(std::ceil(rect.used_w - 0.5)) - 1, 0, rect.w - 1);
		const int band = std::clamp(static_cast<int>(std::lround(options.wall_band_fraction * rect.used_h)), 1, last_row + 1);
		const int row_begin = p_bottom ? last_row - band + 1 : 0;
		for (int r = row_begin; r < row_begin + band; r++) {
			const cv::Vec3f *row = p_completed.ptr<cv::Vec3f>(rect.y + r) + rect.x;
			for (int c = 0; c <= last_col; c++) {
				sum += cv::Vec3d(row[c][0], row[c][1], row[c][2]);
				count++;
			}
		}
	}
	if (count == 0) {
		return options.fallback_color;
	}
	return cv::Vec3f(static_cast<float>(sum[0] / count), static_cast<float>(sum[1] / count), static_cast<float>(sum[2] / count));
}

void TextureInpainter::fill_single(const ChartRect &p_rect, bool p_from_walls, bool p_bottom_band, bool p_walls_have_data,
		const cv::Mat &p_color, const cv::Mat &p_observed, cv::Mat *r_out, GroupFill *r_fill, int *r_filled) const {
	const cv::Rect src(p_rect.x, p_rect.y, p_rect.w, p_rect.h);
	const cv::Mat known = p_observed(src);
	const int observed_count = cv::countNonZero(known);
	const int area = p_rect.w * p_rect.h;
	if (observed_count == area) {
		*r_fill = GroupFill::NothingMissing;
		return;
	}
	cv::Mat missing;
	cv::compare(known, 0, missing, cv::CMP_EQ);
	cv::Mat target = (*r_out)(src);
	if (observed_count > 0) {
		cv::Mat filled;
		telea(p_color(src), known, &filled);
		filled.copyTo(target, missing);
		*r_fill = GroupFill::Inpainted;
	} else if (p_from_walls && p_walls_have_data) {
		// *r_out already holds the completed walls.
		const cv::Vec3f mean = wall_band_mean(*r_out, p_bottom_band);
		target.setTo(cv::Scalar(mean[0], mean[1], mean[2]), missing);
		*r_fill = GroupFill::FromWalls;
	} else {
		target.setTo(cv::Scalar(options.fallback_color[0], options.fallback_color[1], options.fallback_color[2]), missing);
		*r_fill = GroupFill::Fallback;
	}
	*r_filled += area - observed_count;
}

cv::Mat TextureInpainter::inpaint(const CoarseTexture &p_texture, InpaintReport *r_report) const {
	return inpaint(p_texture.color, p_texture.observed, r_report);
}

cv::Mat TextureInpainter::inpaint(const cv::Mat &p_color, const cv::Mat &p_observed, InpaintReport *r_report) const {
	const auto start = std::chrono::steady_clock::now();
	InpaintReport report;
	if (p_color.type() != CV_32FC3 || p_observed.type() != CV_8UC1 || p_color.cols != atlas_width || p_color.rows != atlas_height ||
			p_observed.size() != p_color.size()) {
		if (r_report) {
			*r_report = report;
		}
		return cv::Mat();
	}
	cv::Mat out = p_color.clone();
	fill_walls(p_color, p_observed, &out, &report);
	const bool walls_have_data = report.walls == GroupFill::NothingMissing ? !walls.empty() : report.walls == GroupFill::Inpainted;
	if (has_floor) {
		fill_single(floor_rect, options.fill_floor_from_walls, true, walls_have_data, p_color, p_observed, &out, &report.floor, &report.texels_filled);
	}
	if (has_ceiling) {
		fill_single(ceiling_rect, options.fill_ceiling_from_walls, false, walls_have_data, p_color, p_observed, &out, &report.ceiling, &report.texels_filled);
	}
	report.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
	if (r_report) {
		*r_report = report;
	}
	return out;
}

uint64_t TextureInpainter::request(const CoarseTexture &p_texture) {
	// Copied into buffers the worker is done with (copyTo allocates only when none fits): no
	// allocation a frame on the caller's thread.
	cv::Mat color, observed;
	{
		std::lock_guard<std::mutex> lock(mutex);
		color = std::move(spare_color);
		observed = std::move(spare_observed);
	}
	p_texture.color.copyTo(color);
	p_texture.observed.copyTo(observed);
	uint64_t id = 0;
	{
		std::lock_guard<std::mutex> lock(mutex);
		id = next_id++;
		if (has_pending) {
			// The request not yet taken is replaced: its buffers are free again.
			spare_color = std::move(pending_color);
			spare_observed = std::move(pending_observed);
		}
		pending_color = std::move(color);
		pending_observed = std::move(observed);
		pending_id = id;
		has_pending = true;
	}
	wake.notify_one();
	return id;
}

bool TextureInpainter::try_take_result(cv::Mat *r_color, uint64_t *r_request_id, InpaintReport *r_report) {
	std::lock_guard<std::mutex> lock(mutex);
	if (!has_result) {
		return false;
	}
	has_result = false;
	if (r_color) {
		*r_color = std::move(result_color);
	}
	result_color = cv::Mat();
	if (r_request_id) {
		*r_request_id = result_id;
	}
	if (r_report) {
		*r_report = result_report;
	}
	return true;
}

void TextureInpainter::wait_idle() {
	std::unique_lock<std::mutex> lock(mutex);
	idle.wait(lock, [this]() { return stopping || (!busy && !has_pending); });
}

void TextureInpainter::worker_loop() {
	std::unique_lock<std::mutex> lock(mutex);
	for (;;) {
		wake.wait(lock, [this]() { return stopping || has_pending; });
		if (stopping) {
			break;
		}
		cv::Mat color = std::move(pending_color);
		cv::Mat observed = std::move(pending_observed);
		const uint64_t id = pending_id;
		pending_color = cv::Mat();
		pending_observed = cv::Mat();
		has_pending = false;
		busy = true;
		lock.unlock();

		InpaintReport report;
		cv::Mat completed = inpaint(color, observed, &report);

		lock.lock();
		busy = false;
		spare_color = std::move(color);
		spare_observed = std::move(observed);
		if (id > result_id || !has_result) {
			result_color = std::move(completed);
			result_id = id;
			result_report = report;
			has_result = true;
		}
		if (!has_pending) {
			idle.notify_all();
		}
	}
	busy = false;
	idle.notify_all();
}

} // namespace roomprobe
