#pragma once
// Issue #11's speed targets for slam --recording, and the peers its ratios compare against:
// OpenCV contrib's TSDF and ICP run in this process (opencv_peers.h), Open3D's VoxelBlockGrid read
// from tools/bench/open3d_peer.py's results.

#include "bench_setup.h"
#include "opencv_peers.h"

#include <limits>
#include <string>
#include <vector>

namespace roomprobe::bench {

// Peer time over ours (NaN: the peer did not run).
struct PeerRatios {
	double integration = std::numeric_limits<double>::quiet_NaN();
	double raycast = std::numeric_limits<double>::quiet_NaN();
	double icp = std::numeric_limits<double>::quiet_NaN();
	double open3d_integration = std::numeric_limits<double>::quiet_NaN(); // Open3D VoxelBlockGrid's time / ours
	double open3d_raycast = std::numeric_limits<double>::quiet_NaN();
};

struct SpeedFigures {
	double tracking_ms = 0.0, integration_ms = 0.0, raycast_ms = 0.0, coarse_ms = 0.0, probe_ms = 0.0, full_frame_ms = 0.0;
	int probe_size = 0;
};

// OpenCV's TSDF and ICP on the frames our engine fused, at the poses it tracked (opencv_peers.h).
PeerRatios print_opencv_peers(const std::vector<PeerFrame> &p_frames, const RecordingSetup &p_setup, const SlamFigures &p_figures);
// Open3D's VoxelBlockGrid on the same recording (tools/bench/open3d_peer.py --out FILE, run before
// this process by ./roomprobe bench --open3d): its medians read from FILE, over ours. False, with
// the reason printed, when FILE is unreadable, malformed, or was run with other settings.
bool read_open3d_peer(const std::string &p_file, const RecordingSetup &p_setup, const SlamFigures &p_figures, size_t p_frames, PeerRatios *r_ratios);
// Issue #11's table: the milliseconds on this project's 2-core machine, the ratios anywhere.
void print_speed_targets(const SpeedFigures &p_speed, const PeerRatios &p_ratios);
std::string speed_summary(const SpeedFigures &p_speed, const PeerRatios &p_ratios);

} // namespace roomprobe::bench
