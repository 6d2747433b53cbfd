#version 450
// One frame fused into the listed voxel blocks on the GPU (TsdfIntegratorGpu, tsdf_integrate_gpu.h):
// tsdf_update_voxel_at of slam/tsdf_kernels.h, one invocation per voxel, one workgroup per block.
// The host has chosen the blocks (allocation, the blocks in view, the culling) and computed each
// block's origin in the camera's frame, so every voxel's point is the CPU's: origin + y step_y +
// z step_z, then + x step_x. `precise` keeps the driver from fusing multiply-adds, so the
// arithmetic is the CPU's where the device's division is exact (lavapipe's is).
//
// The pool may be larger than one binding reaches: the host dispatches once per window of it,
// the window's blocks listed from first_block on, their slots counted from the window's start.
//
// Voxels as three words (TsdfVoxel): tsdf (float bits); weight | color_weight << 16; r | g << 8 |
// b << 16. No NaN on the device: depth 0 = no reading, slope -1 = no tangent plane.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 8) in;

struct Block {
	uint slot; // in the window of the voxel pool this dispatch binds
	float x, y, z; // voxel (0, 0, 0) of the block in the camera's frame, metres
};

layout(std430, set = 0, binding = 0) buffer Voxels { uint voxels[]; };
layout(std430, set = 0, binding = 1) readonly buffer Blocks { Block blocks[]; };
layout(std430, set = 0, binding = 2) readonly buffer Frame { uint frame[]; }; // depth, slope (float bits), then the RGB bytes
layout(std430, set = 0, binding = 3) writeonly buffer Flags { uint flags[]; }; // per block: 1 changed, 2 saturated

layout(push_constant) uniform Push {
	float fx, fy, cx, cy;
	int width, height;
	float step_x0, step_x1, step_x2, step_y0, step_y1, step_y2, step_z0, step_z1, step_z2; // one voxel along the grid's axes, camera frame
	float min_slope, truncation_m, color_band_m, behind_limit_m;
	uint full_weight, max_color_weight, early_exits;
	uint slope_offset, rgb_offset; // words into Frame; depth starts at 0
	uint first_block; // this dispatch's first entry of Blocks and Flags
} push;

shared uint any_changed;
shared uint any_unsaturated;

float depth_at(int p_u, int p_v) {
	return uintBitsToFloat(frame[uint(p_v * push.width + p_u)]);
}

uint rgb_byte(uint p_index) {
	return (frame[push.rgb_offset + (p_index >> 2)] >> ((p_index & 3u) * 8u)) & 0xFFu;
}

// tsdf_round_positive and tsdf_floor of tsdf_kernels.h.
int round_positive(float p_x) {
	const int i = int(p_x);
	return i + int(p_x - float(i) >= 0.5);
}
int floor_int(float p_x) {
	const int i = int(p_x);
	return i - int(p_x < float(i));
}

uint blend_channel(uint p_old, uint p_new, float p_cw) {
	precise float mean = (float(p_old) * p_cw + float(p_new)) / (p_cw + 1.0);
	return uint(round_positive(mean));
}

// tsdf_update_voxel_at: true when the voxel changed.
bool update(vec3 pc, inout float tsdf, inout uint weight, inout uint color_weight, inout uint rgb) {
	if (!(pc.z > 0.0)) {
		return false;
	}
	precise float px = push.fx * pc.x / pc.z + push.cx;
	precise float py = push.fy * pc.y / pc.z + push.cy;
	precise float us = px + 0.5, vs = py + 0.5;
	if (!(us >= 0.0 && vs >= 0.0 && us < float(push.width) && vs < float(push.height))) {
		return false;
	}
	const int u = int(us), v = int(vs);
	precise float depth = depth_at(u, v);
	if (!(depth > 0.0)) {
		return false;
	}
	precise float behind = depth - pc.z;
	if (behind < -push.behind_limit_m) {
		return false;
	}
	const float slope = uintBitsToFloat(frame[push.slope_offset + uint(v * push.width + u)]);
	const bool has_plane = slope >= push.min_slope;
	bool far_free = false;
	if (push.early_exits != 0u) {
		precise float spread = 0.5 * push.truncation_m + 1e-5;
		const float factor = has_plane ? slope : 1.0;
		precise float eta_hi = (depth + spread - pc.z) * factor;
		if (eta_hi < -push.truncation_m || (!has_plane && eta_hi < push.truncation_m)) {
			return false;
		}
		precise float eta_lo = (depth - spread - pc.z) * factor;
		far_free = eta_lo >= push.truncation_m && eta_lo >= push.color_band_m;
		if (far_free && tsdf == 1.0 && weight == push.full_weight) {
			return false;
		}
	}
	const int u0 = floor_int(px), v0 = floor_int(py);
	if (!far_free && u0 >= 0 && v0 >= 0 && u0 + 1 < push.width && v0 + 1 < push.height) {
		const float d00 = depth_at(u0, v0), d10 = depth_at(u0 + 1, v0), d01 = depth_at(u0, v0 + 1), d11 = depth_at(u0 + 1, v0 + 1);
		const float lo = min(min(d00, d10), min(d01, d11));
		const float hi = max(max(d00, d10), max(d01, d11));
		precise float spread = hi - lo;
		if (lo > 0.0 && spread < 0.5 * push.truncation_m) {
			precise float fx = px - float(u0), fy = py - float(v0);
			depth = (d00 * (1.0 - fx) + d10 * fx) * (1.0 - fy) + (d01 * (1.0 - fx) + d11 * fx) * fy;
		}
	}
	precise float eta = (depth - pc.z) * (has_plane ? slope : 1.0);
	if (eta < -push.truncation_m || (!has_plane && eta < push.truncation_m)) {
		return false;
	}
	precise float sdf = min(1.0, eta / push.truncation_m);
	const float c = has_plane ? min(1.0, slope) : 0.0;
	precise float scaled = c * c * 32.0; // TSDF_WEIGHT_UNIT
	const uint add = uint(max(1, round_positive(scaled)));
	const float w = float(weight);
	precise float averaged = (tsdf * w + sdf * float(add)) / (w + float(add));
	tsdf = averaged;
	weight = min(weight + add, push.full_weight);
	if (abs(eta) < push.color_band_m) {
		const uint first = uint(v * push.width + u) * 3u;
		const float cw = float(color_weight);
		rgb = blend_channel(rgb & 0xFFu, rgb_byte(first), cw) | (blend_channel((rgb >> 8) & 0xFFu, rgb_byte(first + 1u), cw) << 8) |
				(blend_channel((rgb >> 16) & 0xFFu, rgb_byte(first + 2u), cw) << 16) | (rgb & 0xFF000000u);
		if (color_weight < push.max_color_weight) {
			color_weight++;
		}
	}
	return true;
}

void main() {
	if (gl_LocalInvocationIndex == 0u) {
		any_changed = 0u;
		any_unsaturated = 0u;
	}
	barrier();
	const uint entry = push.first_block + gl_WorkGroupID.x;
	const Block block = blocks[entry];
	const uvec3 l = gl_LocalInvocationID;
	const vec3 step_x = vec3(push.step_x0, push.step_x1, push.step_x2);
	const vec3 step_y = vec3(push.step_y0, push.step_y1, push.step_y2);
	const vec3 step_z = vec3(push.step_z0, push.step_z1, push.step_z2);
	precise vec3 row = vec3(block.x, block.y, block.z) + float(l.y) * step_y + float(l.z) * step_z;
	precise vec3 pc = row + float(l.x) * step_x;
	const uint word = (block.slot * 512u + l.x + 8u * (l.y + 8u * l.z)) * 3u;
	float tsdf = uintBitsToFloat(voxels[word]);
	uint weight = voxels[word + 1u] & 0xFFFFu;
	uint color_weight = voxels[word + 1u] >> 16;
	uint rgb = voxels[word + 2u];
	if (update(pc, tsdf, weight, color_weight, rgb)) {
		voxels[word] = floatBitsToUint(tsdf);
		voxels[word + 1u] = weight | (color_weight << 16);
		voxels[word + 2u] = rgb;
		atomicOr(any_changed, 1u);
	}
	if (!(tsdf == 1.0 && weight == push.full_weight)) {
		atomicOr(any_unsaturated, 1u);
	}
	barrier();
	if (gl_LocalInvocationIndex == 0u) {
		flags[entry] = any_changed | (any_unsaturated == 0u ? 2u : 0u);
	}
}
