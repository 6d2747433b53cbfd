#include "probe_renderer.h"

#include "ggx_prefilter.h"
#include "ggx_prefilter_gpu.h"
#include "sh_project_gpu.h"

#include <tbb/parallel_for.h>

#include <chrono>
#include <cstring>

namespace roomprobe {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point p_start) {
	return std::chrono::duration<double, std::milli>(Clock::now() - p_start).count();
}

// One face as Godot's RGBAH image with mipmaps wants it: level 0, then each half-size level down
// to 1x1, RGBA half floats. The levels are the GGX chain's (ggx_prefilter.h), then box halvings
// of its last level, which no shader reads for roughness.
std::shared_ptr<const PixelBuffer> gpu_face(const std::vector<Cubemap> &p_chain, const cv::Mat &p_distance_m, int p_face,
		const PixelBufferFactory &p_buffers) {
	const std::shared_ptr<PixelBuffer> buffer = make_pixel_buffer(p_buffers, gpu_face_bytes(p_chain.front().size));
	uint8_t *out = buffer->data();
	cv::Mat level, distance = p_distance_m;
	for (size_t m = 0;; m++) {
		if (m < p_chain.size()) {
			level = p_chain[m].faces[size_t(p_face)];
		} else {
			cv::Mat next;
			cv::resize(level, next, cv::Size(std::max(1, level.cols / 2), std::max(1, level.rows / 2)), 0.0, 0.0, cv::INTER_AREA);
			level = next;
		}
		const cv::Size size = level.size();
		// Alpha: the distance to the surface each texel shows (envmap/parallax.h), area-averaged
		// down the chain; 0 where the map has none.
		if (distance.empty()) {
			distance = cv::Mat(size, CV_32FC1, cv::Scalar(0.0f));
		} else if (distance.size() != size) {
			cv::Mat next;
			cv::resize(distance, next, size, 0.0, 0.0, cv::INTER_AREA);
			distance = next;
		}
		cv::Mat rgba;
		const cv::Mat channels[2] = { level, distance };
		rgba.create(level.size(), CV_32FC4);
		const int pairs[8] = { 0, 0, 1, 1, 2, 2, 3, 3 };
		cv::mixChannels(channels, 2, &rgba, 1, pairs, 4);
		// Straight into the buffer: a continuous CV_16FC4 header over its bytes.
		cv::Mat half(level.size(), CV_16FC4, out);
		rgba.convertTo(half, CV_16F);
		CV_Assert(half.data == out); // converted in place, not reallocated
		out += half.total() * half.elemSize();
		if (level.cols == 1 && level.rows == 1) {
			break;
		}
	}
	CV_Assert(out == buffer->data() + buffer->size());
	return buffer;
}

} // namespace

ProbeRenderer::ProbeRenderer(const RoomMesh *p_room, const ProbeRenderSettings &p_settings) :
		settings_(p_settings) {
	if (p_room != nullptr) {
		coarse_ = std::make_unique<CoarseCubemapRenderer>(*p_room);
		coarse_->set_compute(settings_.compute);
	}
}

Cubemap ProbeRenderer::render_faces(const glm::dvec3 &p_position, int p_size, const CoarseMapInput *p_coarse, const DenseMapInput &p_dense,
		DenseRenderStats *r_dense, double *r_coarse_ms, double *r_dense_ms, DenseFaceCache *io_faces) const {
	Clock::time_point start = Clock::now();
	Cubemap map;
	LightingChange cumulative;
	cumulative.valid = true;
	std::array<cv::Mat, 6> observed; // which texels the coarse model's fisheye observations show
	if (coarse_ && p_coarse != nullptr && !p_coarse->atlas.empty()) {
		const Pose room_from_world = inverse(settings_.world_from_room);
		const glm::dvec3 in_room = transform_point(room_from_world, p_position);
		map = coarse_->render(p_coarse->atlas, in_room, p_size, room_from_world.rotation, p_coarse->published);
		if (p_dense.slam != nullptr && settings_.coarse_shell_first && !p_coarse->observed.empty()) {
			observed = coarse_->render_channel(p_coarse->observed, in_room, p_size, room_from_world.rotation, p_coarse->published);
		}
		if (settings_.compute) {
			const std::string problem = coarse_->compute_problem();
			if (!problem.empty()) {
				const std::lock_guard<std::mutex> lock(gpu_mutex);
				note_gpu_failure(problem);
			}
		}
		cumulative = p_coarse->cumulative;
	} else {
		// No observation yet (or no room): black, with the dense model over it, and no distances
		// but the dense model's.
		map = make_cubemap(p_size);
		for (cv::Mat &face : map.distance_m) {
			face = cv::Mat(p_size, p_size, CV_32FC1, cv::Scalar(0.0f));
		}
	}
	*r_coarse_ms = ms_since(start);
	start = Clock::now();
	if (p_dense.slam != nullptr) {
		DenseRenderOptions options;
		options.scale = settings_.dense_scale;
		options.far_m = settings_.dense_far_m;
		options.coarse_observed = observed[0].empty() ? nullptr : &observed;
		options.lut = settings_.rgb_lut_active ? &settings_.rgb_lut : nullptr;
		options.faces_per_render = settings_.dense_faces_per_render;
		const auto reading = p_dense.slam->read_lock(); // no frame half-fused
		*r_dense = p_dense.lighting->render_over(p_dense.slam->volume(), cumulative, p_position, options, &map, io_faces);
	}
	*r_dense_ms = ms_since(start);
	r_dense->milliseconds = *r_dense_ms;
	return map;
}

void ProbeRenderer::render_map(int p_size, const CoarseMapInput *p_coarse, const DenseMapInput &p_dense, const MapOverlay *p_objects,
		const ProbeMap *p_previous, DenseFaceCache *io_faces, ProbeMap *io_map) const {
	const Clock::time_point start = Clock::now();
	io_map->cubemap = render_faces(io_map->position, p_size, p_coarse, p_dense, &io_map->dense, &io_map->coarse_ms, &io_map->dense_ms, io_faces);
	Clock::time_point t = Clock::now();
	if (p_objects != nullptr && p_objects->object_count() > 0) {
		// Lit by the probe's previous map when it has one (it holds the objects too), else by
		// this map's room alone.
		const bool reuse = p_previous != nullptr && p_previous->cubemap.size == p_size;
		const ShCoefficients light = reuse ? p_previous->sh : project(io_map->cubemap);
		io_map->objects = p_objects->draw(io_map->position, light, reuse ? &p_previous->cubemap : nullptr, &io_map->cubemap);
	}
	io_map->sh = project(io_map->cubemap);
	io_map->sh_ms = ms_since(t) - io_map->objects.milliseconds;
	t = Clock::now();
	build_gpu_faces(p_previous, io_map);
	io_map->mips_ms = ms_since(t);
	io_map->total_ms = ms_since(start);
}

// The GGX chain and the faces as Godot takes them. Only what the map changed against the probe's
// previous one is done again: the chain's texels that read a changed face, and the faces whose
// chain or distances changed (dense faces take turns, and the coarse model changes with fisheye
// frames only, so most maps change one or two faces).
size_t gpu_face_bytes(int p_size) {
	size_t texels = 0;
	for (int s = std::max(p_size, 1);; s = std::max(1, s / 2)) {
		texels += size_t(s) * size_t(s);
		if (s == 1) {
			break;
		}
	}
	return texels * 4 * sizeof(uint16_t);
}

void ProbeRenderer::build_gpu_faces(const ProbeMap *p_previous, ProbeMap *io_map) const {
	const int size = io_map->cubemap.size;
	const std::shared_ptr<const GgxFilter> filter = shared_ggx_filter(size, settings_.wait_for_ggx_filter);
	const bool same_kind = p_previous != nullptr && p_previous->cubemap.size == size && p_previous->ggx_mips == (filter != nullptr);
	const uint8_t source_changed = same_kind ? cubemap_changed_faces(p_previous->cubemap, io_map->cubemap) : uint8_t(0x3F);
	uint8_t chain_changed = source_changed;
	std::vector<Cubemap> chain;
	// The device filters whole chains; with nothing changed the CPU path copies the previous one.
	if (filter && settings_.compute && source_changed != 0 && gpu_chain(filter.get(), filter, source_changed, io_map, &chain, &chain_changed)) {
		chain_changed = same_kind ? chain_changed : uint8_t(0x3F);
	} else if (filter) {
		chain = filter->apply(io_map->cubemap, same_kind ? p_previous->ggx_chain : std::vector<Cubemap>{}, source_changed, &chain_changed);
	} else {
		chain = { io_map->cubemap };
	}
	io_map->ggx_mips = filter != nullptr;
	tbb::parallel_for(0, 6, [&](int p_face) {
		const size_t f = size_t(p_face);
		const cv::Mat &distance = io_map->cubemap.distance_m[f];
		const bool same = same_kind && !(chain_changed & (1u << p_face)) && p_previous->gpu_faces[f] && same_pixels(distance, p_previous->cubemap.distance_m[f]);
		io_map->gpu_faces[f] = same ? p_previous->gpu_faces[f] : gpu_face(chain, distance, p_face, settings_.face_buffers);
	});
	if (filter) {
		io_map->ggx_chain = std::move(chain);
	}
}

namespace {

// p_objects' object for p_size, made by p_make(r_error) at the first call; null when the device
// refused it, then or before (r_error says why the first time). Under the renderer's gpu_mutex.
template <typename Objects, typename Make>
auto device_object(Objects &io_objects, int p_size, const Make &p_make, std::string *r_error) -> decltype(p_make(r_error)) {
	if (io_objects.refused.count(p_size) > 0) {
		return nullptr;
	}
	auto &slot = io_objects.made[p_size];
	if (!slot) {
		slot = p_make(r_error);
		if (!slot) {
			io_objects.made.erase(p_size);
			io_objects.refused.insert(p_size);
			return nullptr;
		}
	}
	return slot;
}

} // namespace

bool ProbeRenderer::gpu_chain(const GgxFilter *p_filter, const std::shared_ptr<const GgxFilter> &p_shared, uint8_t p_source_changed, ProbeMap *io_map,
		std::vector<Cubemap> *r_chain, uint8_t *r_changed) const {
	std::shared_ptr<GgxFilterGpu> gpu;
	std::string error;
	{
		const std::lock_guard<std::mutex> lock(gpu_mutex);
		gpu = device_object(gpu_filters, p_filter->face_size(),
				[&](std::string *r_error) { return std::shared_ptr<GgxFilterGpu>(GgxFilterGpu::create(p_shared, settings_.compute, r_error)); }, &error);
		if (!gpu) {
			note_gpu_failure(error);
			return false;
		}
	}
	*r_chain = gpu->apply(io_map->cubemap, &error);
	*r_changed = gpu->dependent_faces(p_source_changed);
	if (r_chain->empty()) {
		const std::lock_guard<std::mutex> lock(gpu_mutex);
		note_gpu_failure(error);
		return false;
	}
	return true;
}

ShCoefficients ProbeRenderer::project(const Cubemap &p_cubemap) const {
	if (!settings_.compute || !is_valid_cubemap(p_cubemap)) {
		return project_sh(p_cubemap);
	}
	const int size = std::min(p_cubemap.size, SH_PROJECTION_FACE_SIZE);
	std::shared_ptr<ShProjectorGpu> gpu;
	std::string error;
	{
		const std::lock_guard<std::mutex> lock(gpu_mutex);
		gpu = device_object(gpu_sh, size,
				[&](std::string *r_error) { return std::shared_ptr<ShProjectorGpu>(ShProjectorGpu::create(size, settings_.compute, r_error)); }, &error);
		if (!gpu) {
			note_gpu_failure(error);
			return project_sh(p_cubemap);
		}
	}
	ShCoefficients sh;
	if (!gpu->project(p_cubemap, &sh, &error)) {
		const std::lock_guard<std::mutex> lock(gpu_mutex);
		note_gpu_failure(error);
		return project_sh(p_cubemap);
	}
	return sh;
}

void ProbeRenderer::note_gpu_failure(const std::string &p_error) const {
	if (!p_error.empty()) {
		gpu_error = p_error;
	}
	gpu_failed++;
}

std::string ProbeRenderer::gpu_problem() const {
	const std::lock_guard<std::mutex> lock(gpu_mutex);
	return gpu_error;
}

} // namespace roomprobe
