#pragma once
// The nodes' setters take whatever a script, a scene file or the inspector gives them. These keep
// each property within what its hint promises and say what happened (issue #17): an enum value
// outside its list is refused with an error and the property keeps its value; a number outside
// its range is clamped with a warning; a non-finite number is refused with an error.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include <rp_godot/godot.h>

namespace roomprobe::property_checks {

// Godot's 3-D render layers: 20 bits (PROPERTY_HINT_LAYERS_3D_RENDER).
constexpr uint32_t RENDER_LAYER_BITS = (1u << 20) - 1;

// True when p_value names one of p_count enum values; otherwise an error naming p_where
// ("Node.property") and the property is left as it was.
inline bool enum_in_range(const char *p_where, int64_t p_value, int64_t p_count) {
	if (p_value >= 0 && p_value < p_count) {
		return true;
	}
	char text[256];
	std::snprintf(text, sizeof(text), "%s must be one of 0..%lld; got %lld; left as it was", p_where,
			(long long)(p_count - 1), (long long)p_value);
	ERR_PRINT(text);
	return false;
}

// p_value clamped to [p_low, p_high] (a warning when it was outside), or p_old with an error
// when it is not a number at all.
inline double clamped(const char *p_where, double p_value, double p_low, double p_high, double p_old, const char *p_unit = "") {
	char text[256];
	if (!std::isfinite(p_value)) {
		std::snprintf(text, sizeof(text), "%s must be a finite number; got %g; left at %g%s", p_where, p_value, p_old, p_unit);
		ERR_PRINT(text);
		return p_old;
	}
	const double value = std::clamp(p_value, p_low, p_high);
	if (value != p_value) {
		std::snprintf(text, sizeof(text), "%s must be within [%g, %g]%s; got %g; clamped to %g%s", p_where, p_low, p_high,
				p_unit, p_value, value, p_unit);
		WARN_PRINT(text);
	}
	return value;
}

inline int64_t clamped_int(const char *p_where, int64_t p_value, int64_t p_low, int64_t p_high, const char *p_unit = "") {
	const int64_t value = std::clamp(p_value, p_low, p_high);
	if (value != p_value) {
		char text[256];
		std::snprintf(text, sizeof(text), "%s must be within [%lld, %lld]%s; got %lld; clamped to %lld%s", p_where,
				(long long)p_low, (long long)p_high, p_unit, (long long)p_value, (long long)value, p_unit);
		WARN_PRINT(text);
	}
	return value;
}

// A render layer mask keeps only Godot's 20 layers, with a warning when other bits were set.
// Setters take int64_t, as scripts give integers: a narrower parameter would let the binding cut
// 2^62 down to 0 unseen.
inline uint32_t render_layers(const char *p_where, int64_t p_mask) {
	const uint64_t mask = uint64_t(p_mask);
	if ((mask & ~uint64_t(RENDER_LAYER_BITS)) != 0) {
		char text[256];
		std::snprintf(text, sizeof(text), "%s has bits above the 20 render layers (0x%llx); kept 0x%x", p_where, (unsigned long long)mask,
				uint32_t(mask & RENDER_LAYER_BITS));
		WARN_PRINT(text);
	}
	return uint32_t(mask & RENDER_LAYER_BITS);
}

// Whether every number of a vector or a transform is finite.
inline bool finite(const godot::Vector3 &p_v) {
	return std::isfinite(p_v.x) && std::isfinite(p_v.y) && std::isfinite(p_v.z);
}
inline bool finite(const godot::Transform3D &p_t) {
	return finite(p_t.basis.rows[0]) && finite(p_t.basis.rows[1]) && finite(p_t.basis.rows[2]) && finite(p_t.origin);
}

} // namespace roomprobe::property_checks
