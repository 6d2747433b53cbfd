#pragma once

// Tiny engine-free vector types shared by the room module.
// Plain aggregates on purpose: the Godot layer converts them to Vector2/Vector3.

namespace roomprobe {

// A 2-D point or vector in double precision. For floorplans, x is world X and
// y is world Z (metres), see floorplan.h.
struct Vec2 {
	double x = 0.0;
	double y = 0.0;
};

// A 3-D point or vector in double precision (world space: Y-up, metres).
struct Vec3 {
	double x = 0.0;
	double y = 0.0;
	double z = 0.0;
};

// Single-precision 2-D vector, as GPU vertex data (atlas UVs).
struct Vec2f {
	float x = 0.0f;
	float y = 0.0f;
};

// Single-precision 3-D vector, as GPU vertex data (positions in metres, unit normals).
struct Vec3f {
	float x = 0.0f;
	float y = 0.0f;
	float z = 0.0f;
};

} // namespace roomprobe
