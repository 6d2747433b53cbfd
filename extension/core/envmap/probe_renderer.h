#pragma once
// ProbeRenderer: one environment map at one point (paper §4.7), from immutable inputs. In order:
// the coarse model's atlas rendered through the room's mesh (coarse_render.h), the dense model
// raycast over it with the lighting change it has not seen (dense_render.h), the other virtual
// objects drawn in (map_overlay.h), 5-band SH, the GGX-prefiltered mip chain (ggx_prefilter.h),
// and the faces as Godot uploads them. The engine's probes and its one-off render_at (the
// evaluation) both render through it, so what is scored is what ships; a second compute backend
// implements these same calls.
//
// Const and safe from several threads at once: the inputs are snapshots, the dense model is read
// under DenseSlam::read_lock, and DenseLighting and DenseFaceCache have their own locks.

#include "coarse_render.h"
#include "dense_render.h"
#include "map_overlay.h"

#include <gpu/compute_device.h>
#include <slam/dense_slam.h>
#include <types/pixel_buffer.h>

#include <array>
#include <atomic>
#include <map>
#include <set>
#include <mutex>
#include <cstdint>
#include <memory>
#include <vector>

namespace roomprobe {

class GgxFilter;
class GgxFilterGpu;
class ShProjectorGpu;

// One environment map at one probe: the float faces, 25 SH coefficients, and the faces as Godot
// uploads them (RGBA half floats with the whole mip chain, level 0 first: the GGX prefiltered
// chain of ggx_prefilter.h, Godot's roughness convention; alpha the distance to the surface).
struct ProbeMap {
	int probe = 0;
	uint64_t version = 0; // per probe: 1, 2, ...
	glm::dvec3 position = glm::dvec3(0.0);
	Cubemap cubemap;
	ShCoefficients sh{};
	// Per face, RGBA halves, level 0 first (gpu_face_bytes); a face the map did not change is the
	// previous map's own (the same pointer), so a node uploads only the faces that changed.
	std::array<std::shared_ptr<const PixelBuffer>, 6> gpu_faces;
	bool ggx_mips = false; // false: box-filtered while the GGX filter is built (ProbeRenderSettings)
	// The GGX chain as floats (level 0: the cubemap's faces): the next map of the probe filters
	// again only the texels that read a changed face (GgxFilter::apply). Empty without ggx_mips.
	std::vector<Cubemap> ggx_chain;
	uint64_t rgbd_sequence = 0, fisheye_sequence = 0; // the newest frames it includes (0: none)
	DenseRenderStats dense;
	VirtualDrawStats objects; // the other virtual objects drawn into it
	double coarse_ms = 0.0, dense_ms = 0.0, sh_ms = 0.0, mips_ms = 0.0 /* GGX chain and half floats */, total_ms = 0.0;
};

struct ProbeRenderSettings {
	Pose world_from_room; // the coarse model lives in the room's frame, the maps' faces in the world's
	// Where the dense model shows the room's shell and the fisheye observed it, keep the coarse
	// model (DenseRenderOptions::coarse_observed). False: the paper's dense-over-all.
	bool coarse_shell_first = true;
	int dense_scale = DenseRenderOptions().scale;
	float dense_far_m = DenseRenderOptions().far_m;
	int dense_faces_per_render = 2; // with a DenseFaceCache (render_map)
	std::array<float, 256> rgb_lut{}; // the RGB camera's 8-bit value -> radiance
	bool rgb_lut_active = false; // false: value / 255
	// Until the GGX filter for a size is built (shared_ggx_filter), mips are box-filtered; true:
	// wait for it instead (the benchmark, the evaluation).
	bool wait_for_ggx_filter = false;
	// The device the coarse render's gather, SH and the GGX chain run on (null: the CPU); a failed
	// dispatch falls back to the CPU for that map and counts in gpu_failures().
	std::shared_ptr<ComputeDevice> compute;
	// Where ProbeMap::gpu_faces are filled (empty: plain vectors).
	PixelBufferFactory face_buffers;
};

// The bytes of one face of ProbeMap::gpu_faces at p_size^2: the whole mip chain of RGBA halves.
size_t gpu_face_bytes(int p_size);

// The coarse model's part of a map: its atlas (completed or raw, CV_32FC3; empty: none yet), where
// the fisheye observed it (CV_32FC1; empty: nowhere known) and its lighting change so far (§4.6).
struct CoarseMapInput {
	cv::Mat atlas;
	cv::Mat observed;
	LightingChange cumulative;
	// Neither Mat is ever written again (a published CoarseSnapshot's): a compute device keeps
	// them between maps (CoarseCubemapRenderer::render).
	bool published = false;
};

// The dense model's part: the model and the lighting state of its colours (null slam: none).
struct DenseMapInput {
	const DenseSlam *slam = nullptr;
	const DenseLighting *lighting = nullptr;
};

class ProbeRenderer {
public:
	// p_room: the room's mesh in the room's frame, outliving the renderer (null: no coarse model;
	// maps then hold the dense model over black).
	ProbeRenderer(const RoomMesh *p_room, const ProbeRenderSettings &p_settings);

	const ProbeRenderSettings &settings() const { return settings_; }
	// The coarse model's renderer (null without a room): the evaluation renders masks through it.
	const CoarseCubemapRenderer *coarse_renderer() const { return coarse_.get(); }

	// The map's float faces alone: the coarse render, then the dense pass over it (p_coarse null or
	// without an atlas: black; p_dense.slam null: no dense pass). io_faces: the probe's dense
	// faces between maps (null: all six raycast now).
	Cubemap render_faces(const glm::dvec3 &p_position, int p_size, const CoarseMapInput *p_coarse, const DenseMapInput &p_dense, DenseRenderStats *r_dense,
			double *r_coarse_ms, double *r_dense_ms, DenseFaceCache *io_faces = nullptr) const;

	// A whole map into io_map (position set by the caller): render_faces, p_objects drawn in (lit by
	// p_previous's SH when it has this size, else this map's room), SH, the GGX chain and the
	// upload faces. Only what changed against p_previous (the probe's last map) is filtered and
	// converted again.
	void render_map(int p_size, const CoarseMapInput *p_coarse, const DenseMapInput &p_dense, const MapOverlay *p_objects, const ProbeMap *p_previous,
			DenseFaceCache *io_faces, ProbeMap *io_map) const;

	size_t gpu_failures() const { return gpu_failed.load(); }
	std::string gpu_problem() const; // why the last map that asked for the device was made on the CPU

private:
	void build_gpu_faces(const ProbeMap *p_previous, ProbeMap *io_map) const;
	// project_sh, on the compute device when there is one (the CPU when it fails).
	ShCoefficients project(const Cubemap &p_cubemap) const;
	void note_gpu_failure(const std::string &p_error) const; // under gpu_mutex; "": the reason stays
	// The GGX chain of io_map's cubemap on the compute device (false: do it on the CPU).
	// r_changed: the output faces that can differ from a previous chain whose source differs in
	// p_source_changed.
	bool gpu_chain(const GgxFilter *p_filter, const std::shared_ptr<const GgxFilter> &p_shared, uint8_t p_source_changed, ProbeMap *io_map,
			std::vector<Cubemap> *r_chain, uint8_t *r_changed) const;

	ProbeRenderSettings settings_;
	std::unique_ptr<CoarseCubemapRenderer> coarse_;
	// The device's objects of one kind, one per face size, made at the first map that needs one; a
	// size the device refused is remembered, not made again every map.
	template <typename T>
	struct DeviceObjects {
		std::map<int, std::shared_ptr<T>> made;
		std::set<int> refused;
	};
	mutable std::mutex gpu_mutex; // the device objects, gpu_error
	mutable DeviceObjects<GgxFilterGpu> gpu_filters;
	mutable DeviceObjects<ShProjectorGpu> gpu_sh;
	mutable std::string gpu_error;
	mutable std::atomic<size_t> gpu_failed{ 0 };
};

} // namespace roomprobe
