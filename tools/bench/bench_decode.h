#pragma once
// roomprobe_bench decode --recording DIR: what reading a recording's frames costs (issue #36: the
// decoding must not be the bottleneck in real time), and what each frame encoding would cost on
// the same frames.
//
// 1. As stored: every RGB-D and fisheye frame read through RecordingReader (read_rgbd,
//    read_fisheye: the file read, decoded, checked and converted, as the engine's capture thread
//    pays it), after one pass that warms the page cache; the median and mean per frame over
//    --repeats passes, and the files' bytes per frame.
// 2. The same frames in memory, through each encoding: PNG (libpng at zlib level 1, as the writer
//    writes it, with the B, G, R swap the writer and the reader make for colour) and raw frames
//    (io/raw_frame.h) at each zstd level of --levels: encode and decode milliseconds (median over
//    frames and passes) and bytes per frame, each decoded frame checked bit for bit against the
//    original. HDR fisheye frames are compared as half-float raw frames (their EXR cost is in 1).
//
// Ends with one line 'summary: mode=decode key=value ...'.

#include <string>
#include <vector>

namespace roomprobe::bench {

struct DecodeBenchOptions {
	std::string recording;
	long frames = -1; // per stream; -1: all
	int repeats = 3; // timed passes
	std::vector<int> levels = { 1, 2, 3 }; // zstd levels compared
};

// 0, or 1 when the recording does not open or a frame fails to read or round-trip.
int bench_decode(const DecodeBenchOptions &p_options);

} // namespace roomprobe::bench
