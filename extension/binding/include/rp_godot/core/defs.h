#pragma once
// Basic definitions shared by the whole binding.

#include <rp_godot/gen/gdextension_interface.h>

#include <cstddef>
#include <cstdint>

#if defined(_WIN32)
#define GDE_EXPORT __declspec(dllexport)
#else
#define GDE_EXPORT __attribute__((visibility("default")))
#endif

namespace godot {

// RoomProbe targets single-precision engine builds (the generator refuses others).
using real_t = float;

} // namespace godot
