#pragma once
// The core's one thread pool is TBB's: every parallel loop (SLAM, the coarse model, the maps) runs
// on it, so one setting bounds them all. A program bounds the process with
// tbb::global_control (the tools' --threads), and the engine confines a stage to a
// tbb::task_arena (LiveRoomConfig::render_threads). OpenCV's own functions (resize, remap) keep
// OpenCV's pool; no loop of ours runs there.

#include <opencv2/core/types.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace roomprobe {

// p_body(cv::Range) over sub-ranges of p_range, as cv::parallel_for_ calls it: a body must work
// on any sub-range, in any order, on any thread.
template <typename Body>
void parallel_for(const cv::Range &p_range, const Body &p_body) {
	tbb::parallel_for(tbb::blocked_range<int>(p_range.start, p_range.end),
			[&p_body](const tbb::blocked_range<int> &p_part) { p_body(cv::Range(p_part.begin(), p_part.end())); });
}

} // namespace roomprobe
