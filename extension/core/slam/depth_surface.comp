#version 450
// One pyramid level's surface on the GPU, written straight into icp_reduce.comp's Frame layout
// (IcpReducerGpu::build_frame): per sampled pixel its camera-frame vertex (compute_vertex_map) and
// normal (normal_pixel in slam/icp_kernels.h, from the four neighbours' vertices, made here from
// their depths as the CPU makes its vertex map), its intensity and the validity flags.

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 0) readonly buffer Depth { float depth[]; };
layout(std430, set = 0, binding = 1) readonly buffer Intensity { float intensity[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Frame { float frame[]; }; // 8 floats per sampled pixel

layout(push_constant) uniform Push {
	uint width, height, depth_offset, intensity_offset; // the level: pixels, first floats
	uint has_intensity, stride, columns, rows; // every stride-th pixel of every stride-th row; the sampled grid's size
	uint frame_offset; // first float of the level in Frame
	float fx, fy, cx, cy; // the level's camera, pixels
	float max_jump_relative; // no normal across a z step larger than this times z
} push;

vec3 vertex(int x, int y) {
	const float d = depth[push.depth_offset + uint(y) * push.width + uint(x)];
	return vec3((float(x) - push.cx) / push.fx * d, (float(y) - push.cy) / push.fy * d, d);
}

// The unit normal at (x, y), towards the camera; false where normal_pixel gives none.
bool normal_at(int x, int y, vec3 c, out vec3 n) {
	n = vec3(0.0);
	if (x < 1 || y < 1 || x >= int(push.width) - 1 || y >= int(push.height) - 1) {
		return false;
	}
	const vec3 l = vertex(x - 1, y), r = vertex(x + 1, y), u = vertex(x, y - 1), d = vertex(x, y + 1);
	if (!(c.z > 0.0 && l.z > 0.0 && r.z > 0.0 && u.z > 0.0 && d.z > 0.0)) {
		return false;
	}
	const float jump = push.max_jump_relative * c.z;
	if (abs(l.z - c.z) > jump || abs(r.z - c.z) > jump || abs(u.z - c.z) > jump || abs(d.z - c.z) > jump) {
		return false;
	}
	n = cross(r - l, d - u);
	const float len = length(n);
	if (!(len > 0.0)) {
		return false;
	}
	n /= len;
	n = dot(n, c) > 0.0 ? -n : n;
	return true;
}

void main() {
	const uint sx = gl_GlobalInvocationID.x, sy = gl_GlobalInvocationID.y;
	if (sx >= push.columns || sy >= push.rows) {
		return;
	}
	const int x = int(sx * push.stride), y = int(sy * push.stride);
	const uint base = push.frame_offset + 8u * (sy * push.columns + sx);
	const vec3 c = vertex(x, y);
	vec3 n;
	const bool geometry = c.z > 0.0 && normal_at(x, y, c, n);
	for (uint k = 0u; k < 8u; k++) {
		frame[base + k] = 0.0;
	}
	if (!geometry) {
		return;
	}
	frame[base] = c.x;
	frame[base + 1u] = c.y;
	frame[base + 2u] = c.z;
	frame[base + 3u] = n.x;
	frame[base + 4u] = n.y;
	frame[base + 5u] = n.z;
	const bool has_intensity = push.has_intensity != 0u;
	frame[base + 6u] = has_intensity ? intensity[push.intensity_offset + uint(y) * push.width + uint(x)] : 0.0;
	frame[base + 7u] = has_intensity ? 3.0 : 1.0;
}
