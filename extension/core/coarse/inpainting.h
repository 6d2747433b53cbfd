#pragma once
// Completing the never-observed texels of the coarse texture (paper §4.5).
//
// Telea inpainting (cv::inpaint, INPAINT_TELEA) is run PER SURFACE GROUP so that colours do not
// bleed between surfaces of different materials: the walls together, the floor, the ceiling. Inside
// a group only the group's observed texels are "known"; every other texel of the working image
// (other groups, atlas padding) is part of the inpaint mask, so Telea can only propagate colour
// from the group's own observations.
//
// Walls are inpainted on a STRIP: the wall charts side by side in floorplan order (wall i's right
// edge touches wall i + 1's left edge in the room), wrapped around at both ends, so that colour
// propagates across room corners as it does in the room, not across the atlas packing.
//
// Precision: the texture is linear CV_32FC3, possibly HDR (values > 1). cv::inpaint takes 8-bit
// 1/3-channel, 16-bit unsigned 1-channel or 32-bit float 1-channel images. An 8-bit round trip
// would clip HDR values and quantise dark linear values coarsely (1/255 steps are large in linear
// light). The 32-bit float path was the first choice but is unusable in the OpenCV in use (4.10):
// on a 0.20..0.33 ramp with a 4x4 hole it returned values from -0.86 to 1.31. So each channel is
// inpainted separately as CV_16UC1 fixed point, scaled so that the group's largest known value of
// that channel maps to 65535 (quantisation step: that value / 65535, about 1.5e-5 for a [0, 1]
// texture, whatever the HDR range). Three Telea passes share one mask.
//
// Groups with no observed texel at all: the floor takes the mean colour of the LOWER band of the
// walls (after the walls are completed, so observed wall texels where there are any, else the wall
// colour Telea propagated downwards), as the paper propagates wall colour onto a not yet observed
// floor; a uniform colour is used rather than inpainting from wall texels placed around the floor
// chart, since the floor chart's outline does not match the walls' bottom edges texel by texel
// and Telea over a whole floor chart from its border only yields a blurred average anyway. As an
// extension, the ceiling does the same with the walls' UPPER band. Walls with nothing observed
// (and anything when nothing at all is observed) get options.fallback_color, the paper's neutral
// grey.
//
// Only texels inside a chart's rect that have never been observed are written (the unused
// rounding margin of a rect and the floor/ceiling rect's corners outside the polygon are filled
// too, which helps texture filtering at chart borders); observed texels and atlas padding are
// copied unchanged. The result is a separate image: CoarseTexture::color keeps only observations.
//
// Incremental re-application off the frame's critical path: request() hands a snapshot to a
// worker thread that always inpaints the NEWEST pending request (older pending ones are dropped);
// try_take_result() picks up a finished result without blocking.

#include <coarse/coarse_texture.h>
#include <room/room_mesh.h>

#include <io/opencv.h>

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace roomprobe {

struct InpaintingOptions {
	double inpaint_radius_texels = 3.0; // Telea's neighbourhood radius, texels; > 0.
	// Rows in the bottom (floor fill) or top (ceiling fill) fraction of each wall's height form the
	// wall band a not yet observed floor (ceiling) takes its mean colour from; in (0, 1].
	double wall_band_fraction = 0.2;
	bool fill_floor_from_walls = true; // Paper §4.5; false: an unobserved floor gets fallback_color.
	bool fill_ceiling_from_walls = true; // Extension; false: an unobserved ceiling gets fallback_color.
	cv::Vec3f fallback_color = cv::Vec3f(0.5f, 0.5f, 0.5f); // Linear colour where nothing can be propagated.
};

// How each group was completed by the last inpaint().
enum class GroupFill {
	NothingMissing, // Every texel of the group was observed.
	Inpainted, // Telea from the group's own observed texels.
	FromWalls, // Uniform mean of the walls' lower (floor) or upper (ceiling) band.
	Fallback, // options.fallback_color.
};

struct InpaintReport {
	GroupFill walls = GroupFill::NothingMissing;
	GroupFill floor = GroupFill::NothingMissing;
	GroupFill ceiling = GroupFill::NothingMissing;
	int texels_filled = 0; // Texels written (never observed, inside a chart rect).
	double milliseconds = 0.0; // Wall time of the inpaint() call.
};

const char *group_fill_name(GroupFill p_fill);

class TextureInpainter {
public:
	// Keeps what it needs of p_mesh's chart layout (the mesh itself may go away).
	explicit TextureInpainter(const RoomMesh &p_mesh, const InpaintingOptions &p_options = InpaintingOptions());
	~TextureInpainter(); // Stops the worker, waiting for an inpaint in progress to finish (RAII join).

	TextureInpainter(const TextureInpainter &) = delete;
	TextureInpainter &operator=(const TextureInpainter &) = delete;

	// Synchronous: the completed colour image (CV_32FC3, the atlas's size) for p_texture's colour
	// and observed mask, which must have the mesh's atlas size and CV_32FC3 / CV_8UC1 types (an
	// empty Mat is returned otherwise). Thread-safe (const, uses only immutable layout data).
	cv::Mat inpaint(const CoarseTexture &p_texture, InpaintReport *r_report = nullptr) const;
	cv::Mat inpaint(const cv::Mat &p_color, const cv::Mat &p_observed, InpaintReport *r_report = nullptr) const;

	// Asynchronous: copies p_texture's colour and observed mask and queues them for the worker,
	// replacing any request it has not started yet. Returns the request's id (1, 2, ...).
	uint64_t request(const CoarseTexture &p_texture);
	// If a result newer than the last one taken is ready, moves it to *r_color (and its request id
	// to *r_request_id, its report to *r_report, each if not null) and returns true; never blocks.
	bool try_take_result(cv::Mat *r_color, uint64_t *r_request_id = nullptr, InpaintReport *r_report = nullptr);
	// Blocks until no request is pending or running (for tests and shutdown paths).
	void wait_idle();

	const InpaintingOptions &get_options() const { return options; }

private:
	struct ChartRect {
		int x = 0, y = 0, w = 0, h = 0;
		double used_w = 0.0, used_h = 0.0;
	};

	void worker_loop();
	// Inpaints p_color (CV_32FC3) where p_known is 0; false when nothing is known.
	bool telea(const cv::Mat &p_color, const cv::Mat &p_known, cv::Mat *r_out) const;
	void fill_walls(const cv::Mat &p_color, const cv::Mat &p_observed, cv::Mat *r_out, InpaintReport *r_report) const;
	void fill_single(const ChartRect &p_rect, bool p_from_walls, bool p_bottom_band, bool p_walls_have_data,
			const cv::Mat &p_color, const cv::Mat &p_observed, cv::Mat *r_out, GroupFill *r_fill, int *r_filled) const;
	cv::Vec3f wall_band_mean(const cv::Mat &p_completed, bool p_bottom) const;

	InpaintingOptions options;
	int atlas_width = 0;
	int atlas_height = 0;
	std::vector<ChartRect> walls; // In floorplan order.
	ChartRect floor_rect;
	ChartRect ceiling_rect;
	bool has_floor = false;
	bool has_ceiling = false;
	std::vector<int> wall_strip_x; // Column of walls[i] in the strip.
	int strip_width = 0; // Without wrap padding.
	int strip_height = 0;
	int strip_pad = 0; // Wrap-around columns on each side.

	// Worker state.
	std::mutex mutex;
	std::condition_variable wake;
	std::condition_variable idle;
	bool stopping = false;
	bool busy = false;
	bool has_pending = false;
	cv::Mat pending_color;
	cv::Mat pending_observed;
	cv::Mat spare_color, spare_observed; // a request's buffers once the worker is done with them, for the next request
	uint64_t pending_id = 0;
	uint64_t next_id = 1;
	bool has_result = false;
	cv::Mat result_color;
	uint64_t result_id = 0;
	InpaintReport result_report;
	std::thread worker; // Last member: started after everything else is constructed.
};

} // namespace roomprobe
