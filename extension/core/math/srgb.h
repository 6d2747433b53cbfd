#pragma once
// The sRGB transfer function (IEC 61966-2-1), the one place the project writes it: encoded
// values in [0, 1] to linear and back.

#include <cmath>

namespace roomprobe {

inline double srgb_decode(double p_encoded) {
	return p_encoded <= 0.04045 ? p_encoded / 12.92 : std::pow((p_encoded + 0.055) / 1.055, 2.4);
}

inline double srgb_encode(double p_linear) {
	return p_linear <= 0.0031308 ? 12.92 * p_linear : 1.055 * std::pow(p_linear, 1.0 / 2.4) - 0.055;
}

} // namespace roomprobe
