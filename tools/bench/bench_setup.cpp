#include "bench_setup.h"

#include <camera/pinhole_camera.h>
#include <engine/engine_config.h>
#include <rig/photometry.h>

#include <filesystem>

namespace roomprobe::bench {

namespace {

bool is_synthetic_recording(const std::string &p_folder) {
	std::error_code ec;
	return std::filesystem::exists(std::filesystem::path(p_folder) / "synth.yaml", ec);
}

// The probe's map is rendered at probe 0, or the floorplan's centre at 0.9 m when room.yaml has none.
glm::dvec3 probe_position(const RoomInfo &p_room, bool *r_from_file) {
	*r_from_file = !p_room.probes.empty();
	if (*r_from_file) {
		return p_room.probes[0];
	}
	glm::dvec3 centre(0.0, 0.9, 0.0);
	for (const Vec2 &p : p_room.floorplan.points) {
		centre.x += p.x / double(p_room.floorplan.points.size());
		centre.z += p.y / double(p_room.floorplan.points.size());
	}
	return centre;
}

// Why the engine cannot run on p_reader (dense SLAM alone then), or "".
std::string engine_skip_reason(const RecordingReader &p_reader) {
	if (!p_reader.has_room()) {
		return "no room (no room.yaml)";
	}
	if (!p_reader.get_rig().has_fisheye()) {
		return "no fisheye stream (the rig has no fisheye)";
	}
	if (p_reader.fisheye_count() == 0) {
		return "no fisheye stream (no fisheye frames)";
	}
	return "";
}

// What the bench sets on top of the recording's configuration.
void apply_bench_settings(const Arguments &p_args, const PinholeParams &p_camera, int p_probe_size, LiveRoomConfig *r_config) {
	LiveRoomConfig &config = *r_config;
	config.wait_for_ggx_filter = true; // every map timed is the prefiltered one
	config.rig.rgb = p_camera;
	config.slam = p_args.slam;
	config.coarse_poses = PoseSource::Tracked; // the ground truth is for the ATE only
	config.dense_poses = PoseSource::Tracked;
	config.coarse.inpaint_async = true; // as CoarseRoomModel: off the frame's critical path
	config.coarse.lighting = true;
	config.coarse.lighting_model = LightingModel::GAIN_ROBUST;
	config.coarse.cubemap_size = p_probe_size;
	config.mesh_interval_frames = MESH_INTERVAL;
	config.compute_backend = p_args.backend;
}

} // namespace

bool camera_from_arguments(const Arguments &p_args, const PinholeParams &p_base, PinholeParams *r_camera, std::string *r_note) {
	*r_camera = p_base;
	r_note->clear();
	if (!p_args.rig_file.empty()) {
		const RigLoadResult rig = load_rig(p_args.rig_file);
		if (!rig.ok) {
			std::fprintf(stderr, "roomprobe_bench: --rig: %s\n", rig.error.c_str());
			return false;
		}
		*r_camera = rig.rig.rgb;
		*r_note = "--rig " + p_args.rig_file;
	} else if (p_args.has_intrinsics) {
		*r_camera = PinholeParams();
		r_camera->width = p_base.width;
		r_camera->height = p_base.height;
		r_camera->fx = p_args.intrinsics[0];
		r_camera->fy = p_args.intrinsics[1];
		r_camera->cx = p_args.intrinsics[2];
		r_camera->cy = p_args.intrinsics[3];
		*r_note = "--intrinsics";
	}
	return true;
}

bool open_recording(const Arguments &p_args, int p_default_probe_size, RecordingSetup *r_setup) {
	r_setup->probe_size = p_args.probe_size > 0 ? p_args.probe_size : p_default_probe_size;
	PlayerOptions options;
	options.max_rgbd_frames = p_args.frames > 0 ? size_t(p_args.frames) : 0;
	const std::string opened = open_player(p_args.recording, options, &r_setup->player);
	if (!opened.empty()) {
		std::fprintf(stderr, "roomprobe_bench: --recording: %s\n", opened.c_str());
		return false;
	}
	const RecordingReader &reader = r_setup->reader();
	if (reader.rgbd_count() == 0) {
		std::fprintf(stderr, "roomprobe_bench: --recording %s: no usable RGB-D frames\n", p_args.recording.c_str());
		return false;
	}
	if (!camera_from_arguments(p_args, reader.get_rig().rgb, &r_setup->camera, &r_setup->camera_note)) {
		return false;
	}
	const PinholeParams &rig_rgb = reader.get_rig().rgb;
	if (r_setup->camera.width != rig_rgb.width || r_setup->camera.height != rig_rgb.height) {
		std::fprintf(stderr, "roomprobe_bench: --rig %s: its RGB-D camera is %dx%d, the recording's images %dx%d\n", p_args.rig_file.c_str(),
				r_setup->camera.width, r_setup->camera.height, rig_rgb.width, rig_rgb.height);
		return false;
	}
	r_setup->synthetic = is_synthetic_recording(p_args.recording);
	r_setup->engine_skip = engine_skip_reason(reader);
	if (!r_setup->engine_skip.empty()) {
		return true; // SLAM only: no engine to configure
	}
	const std::string error = config_from_recording(reader, true, &r_setup->config);
	if (!error.empty()) {
		std::fprintf(stderr, "roomprobe_bench: --recording %s: %s\n", p_args.recording.c_str(), error.c_str());
		return false;
	}
	apply_bench_settings(p_args, r_setup->camera, r_setup->probe_size, &r_setup->config);
	r_setup->probe = probe_position(reader.get_room(), &r_setup->probe_from_file);
	return true;
}

bool configure_engine(const RecordingSetup &p_setup, const std::string &p_what, LiveRoom *r_engine) {
	const std::string error = r_engine->configure(p_setup.config);
	if (!error.empty()) {
		std::fprintf(stderr, "roomprobe_bench: %s: %s\n", p_what.c_str(), error.c_str());
		return false;
	}
	return true;
}

void print_recording_header(const char *p_mode, const Arguments &p_args, const RecordingSetup &p_setup, const LiveRoom &p_engine) {
	const Rig &rig = p_setup.config.rig;
	const RecordingReader &reader = p_setup.reader();
	const RigPhotometry &photometry = p_setup.config.photometry;
	std::printf("roomprobe_bench %s --recording %s\n", p_mode, p_args.recording.c_str());
	std::printf("  RGB-D %dx%d, %zu of %zu frames; fisheye %dx%d, %zu frames in the recording; %zu recording issues\n", rig.rgb.width, rig.rgb.height,
			p_setup.rgbd_total(), reader.rgbd_count(), rig.fisheye.width, rig.fisheye.height, reader.fisheye_count(), reader.get_issues().size());
	print_issues(stdout, reader);
	std::printf("  intrinsics (%s): fx %.3f fy %.3f cx %.3f cy %.3f%s; depth scale %.6f m per unit\n",
			p_setup.camera_note.empty() ? "rig.yaml" : p_setup.camera_note.c_str(), rig.rgb.fx, rig.rgb.fy, rig.rgb.cx, rig.rgb.cy,
			has_pinhole_distortion(rig.rgb) ? " (with distortion)" : "", rig.depth_scale_m);
	std::printf("  probe %s at [%.2f %.2f %.2f], %d^2; coarse texel %.0f mm, async inpainting, gain lighting\n",
			p_setup.probe_from_file ? "0" : "(none in room.yaml: floorplan centre)", p_setup.probe.x, p_setup.probe.y, p_setup.probe.z, p_setup.probe_size,
			1000.0 * p_setup.config.coarse.texel_size_m);
	print_settings(p_setup.config.slam);
	if (photometry.known) {
		const glm::dvec3 &g = photometry.fisheye.channel_gains;
		std::printf("  photometry: fisheye gains %.3f %.3f %.3f, %zu vignetting nodes, %s exposure; RGB gain %.3f\n", g.x, g.y, g.z,
				photometry.fisheye.vignetting.size(), std::isfinite(photometry.fisheye.reference_exposure_us) ? "per-frame" : "fixed",
				photometry.rgb.channel_gains.y);
	} else {
		std::printf("  photometry: unknown (frames as recorded)\n");
	}
	std::printf("  engine: LiveRoom, tracked poses for both models, re-mesh every %d fused frames, dense pass at 1/%d, %d render thread(s)\n",
			p_setup.config.mesh_interval_frames, p_setup.config.dense_render_scale, p_setup.config.render_threads);
	std::printf("  backend (tracking, integration, raycasts, the coarse render's gather, the GGX prefilter, SH): %s\n", p_engine.stats().compute.c_str());
	print_threads();
}

} // namespace roomprobe::bench
