#pragma once
// Godot's math builtins as plain structs with the engine's memory layout (single precision).
// layout_checks.gen.cpp asserts every size and member offset against the engine's dump.
// Only what the Godot-facing layer needs is here; numerical work belongs in extension/core.

#include <rp_godot/core/defs.h>

#include <cmath>

namespace godot {

struct Vector2 {
	real_t x = 0, y = 0;
	constexpr Vector2() = default;
	constexpr Vector2(real_t p_x, real_t p_y) : x(p_x), y(p_y) {}
	constexpr Vector2 operator+(const Vector2 &p_v) const { return { x + p_v.x, y + p_v.y }; }
	constexpr Vector2 operator-(const Vector2 &p_v) const { return { x - p_v.x, y - p_v.y }; }
	constexpr Vector2 operator*(real_t p_s) const { return { x * p_s, y * p_s }; }
	constexpr bool operator==(const Vector2 &p_v) const { return x == p_v.x && y == p_v.y; }
	real_t length() const { return std::sqrt(x * x + y * y); }
};

struct Vector2i {
	int32_t x = 0, y = 0;
	constexpr Vector2i() = default;
	constexpr Vector2i(int32_t p_x, int32_t p_y) : x(p_x), y(p_y) {}
	constexpr bool operator==(const Vector2i &p_v) const { return x == p_v.x && y == p_v.y; }
};

struct Vector3 {
	real_t x = 0, y = 0, z = 0;
	constexpr Vector3() = default;
	constexpr Vector3(real_t p_x, real_t p_y, real_t p_z) : x(p_x), y(p_y), z(p_z) {}
	constexpr Vector3 operator+(const Vector3 &p_v) const { return { x + p_v.x, y + p_v.y, z + p_v.z }; }
	constexpr Vector3 operator-(const Vector3 &p_v) const { return { x - p_v.x, y - p_v.y, z - p_v.z }; }
	constexpr Vector3 operator-() const { return { -x, -y, -z }; }
	constexpr Vector3 operator*(real_t p_s) const { return { x * p_s, y * p_s, z * p_s }; }
	constexpr bool operator==(const Vector3 &p_v) const { return x == p_v.x && y == p_v.y && z == p_v.z; }
	constexpr real_t dot(const Vector3 &p_v) const { return x * p_v.x + y * p_v.y + z * p_v.z; }
	constexpr Vector3 cross(const Vector3 &p_v) const { return { y * p_v.z - z * p_v.y, z * p_v.x - x * p_v.z, x * p_v.y - y * p_v.x }; }
	real_t length() const { return std::sqrt(dot(*this)); }
};

struct Vector3i {
	int32_t x = 0, y = 0, z = 0;
	constexpr Vector3i() = default;
	constexpr Vector3i(int32_t p_x, int32_t p_y, int32_t p_z) : x(p_x), y(p_y), z(p_z) {}
	constexpr bool operator==(const Vector3i &p_v) const { return x == p_v.x && y == p_v.y && z == p_v.z; }
};

struct Vector4 {
	real_t x = 0, y = 0, z = 0, w = 0;
	constexpr Vector4() = default;
	constexpr Vector4(real_t p_x, real_t p_y, real_t p_z, real_t p_w) : x(p_x), y(p_y), z(p_z), w(p_w) {}
	constexpr bool operator==(const Vector4 &p_v) const { return x == p_v.x && y == p_v.y && z == p_v.z && w == p_v.w; }
};

struct Vector4i {
	int32_t x = 0, y = 0, z = 0, w = 0;
	constexpr Vector4i() = default;
	constexpr Vector4i(int32_t p_x, int32_t p_y, int32_t p_z, int32_t p_w) : x(p_x), y(p_y), z(p_z), w(p_w) {}
	constexpr bool operator==(const Vector4i &p_v) const { return x == p_v.x && y == p_v.y && z == p_v.z && w == p_v.w; }
};

struct Rect2 {
	Vector2 position, size;
	constexpr Rect2() = default;
	constexpr Rect2(real_t p_x, real_t p_y, real_t p_w, real_t p_h) : position(p_x, p_y), size(p_w, p_h) {}
	constexpr bool operator==(const Rect2 &p_r) const { return position == p_r.position && size == p_r.size; }
};

struct Rect2i {
	Vector2i position, size;
	constexpr Rect2i() = default;
	constexpr Rect2i(int32_t p_x, int32_t p_y, int32_t p_w, int32_t p_h) : position(p_x, p_y), size(p_w, p_h) {}
	constexpr bool operator==(const Rect2i &p_r) const { return position == p_r.position && size == p_r.size; }
};

struct Transform2D {
	Vector2 columns[3] = { { 1, 0 }, { 0, 1 }, { 0, 0 } };
};

struct Plane {
	Vector3 normal;
	real_t d = 0;
	constexpr bool operator==(const Plane &p_p) const { return normal == p_p.normal && d == p_p.d; }
};

struct Quaternion {
	real_t x = 0, y = 0, z = 0, w = 1;
	constexpr bool operator==(const Quaternion &p_q) const { return x == p_q.x && y == p_q.y && z == p_q.z && w == p_q.w; }
};

struct AABB {
	Vector3 position, size;
	constexpr bool operator==(const AABB &p_a) const { return position == p_a.position && size == p_a.size; }
};

// Rows of a 3x3 matrix, as Godot stores them.
struct Basis {
	Vector3 rows[3] = { { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 } };
	constexpr Vector3 xform(const Vector3 &p_v) const { return { rows[0].dot(p_v), rows[1].dot(p_v), rows[2].dot(p_v) }; }
	constexpr bool operator==(const Basis &p_b) const { return rows[0] == p_b.rows[0] && rows[1] == p_b.rows[1] && rows[2] == p_b.rows[2]; }
};

struct Transform3D {
	Basis basis;
	Vector3 origin;
	constexpr Vector3 xform(const Vector3 &p_v) const { return basis.xform(p_v) + origin; }
	constexpr bool operator==(const Transform3D &p_t) const { return basis == p_t.basis && origin == p_t.origin; }
};

struct Projection {
	Vector4 columns[4] = { { 1, 0, 0, 0 }, { 0, 1, 0, 0 }, { 0, 0, 1, 0 }, { 0, 0, 0, 1 } };
};

struct Color {
	float r = 0, g = 0, b = 0, a = 1;
	constexpr Color() = default;
	constexpr Color(float p_r, float p_g, float p_b, float p_a = 1.0f) : r(p_r), g(p_g), b(p_b), a(p_a) {}
	constexpr bool operator==(const Color &p_c) const { return r == p_c.r && g == p_c.g && b == p_c.b && a == p_c.a; }
};

} // namespace godot
