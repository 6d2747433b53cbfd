#pragma once
// splitmix64 (Steele, Lea and Flood 2014): a 64-bit mix for deterministic per-item seeds and
// jitter (the synthetic rig's noise, the PRT bake's stratified directions).

#include <cstdint>

namespace roomprobe {

inline uint64_t splitmix64(uint64_t p_x) {
	p_x += 0x9e3779b97f4a7c15ULL;
	p_x = (p_x ^ (p_x >> 30)) * 0xbf58476d1ce4e5b9ULL;
	p_x = (p_x ^ (p_x >> 27)) * 0x94d049bb133111ebULL;
	return p_x ^ (p_x >> 31);
}

} // namespace roomprobe
