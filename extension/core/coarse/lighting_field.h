#pragma once
// The gain field of a lighting change (issue #42, beyond the paper's §4.6): log g_c(x) = a_c +
// s . x, one slope s shared by the channels (a light changes how much light a place gets; its
// colour is in the a_c). Fitted to the (old, new) pairs with their positions, robustly (Tukey's
// biweight on the log ratios) and with a Gaussian prior on s (ridge), from the one-gain start.

#include "lighting.h"

namespace roomprobe {

// p_valid: usable pairs, each with a finite position; p_gains: the one-gain fit. Fills
// r_change->gain (at the world origin) and r_change->log_slope; false (r_change untouched) when
// the fit is not possible (too few pairs, no spread).
bool fit_lighting_field(const std::vector<LightingSample> &p_valid, const cv::Vec3d &p_gains, const LightingOptions &p_options,
		LightingChange *r_change);

} // namespace roomprobe
