#pragma once
// The frames the GPU TSDF tests fuse (test_gpu_integration.cpp, test_gpu_raycast.cpp): the
// synthetic living room at 320x240 and true poses, every fourth frame from 0.5 s (more of the room
// per frame), each with its own noise.

#include "slam/tsdf_volume.h"
#include "synth_test_frames.h"

namespace gpu_test_fusion {

// Fuses frame p_frame into r_volume; what integrate() said.
inline roomprobe::IntegrationStats fuse(roomprobe::TsdfVolume *r_volume, int p_frame) {
	const double t = 0.5 + p_frame * 4.0 / 30.0;
	const roomprobe::Pose pose = synth_frames::living_room().trajectory.world_from_rgb(t);
	const synth_frames::Frame shot = synth_frames::render_living_room(pose, t, true, uint64_t(p_frame) + 21);
	return r_volume->integrate(shot.depth_m, shot.rgb, roomprobe::pinhole_intrinsics(synth_frames::half_camera()), pose);
}

} // namespace gpu_test_fusion
