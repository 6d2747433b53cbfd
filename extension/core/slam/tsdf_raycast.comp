#version 450
// The TSDF seen from a pose on the GPU (TsdfRaycasterGpu, tsdf_raycast_gpu.h): one invocation per
// pixel runs tsdf_raycast_pixel of slam/tsdf_kernels.h (the march through unallocated blocks,
// sphere tracing, half-voxel steps near the surface, regula falsi, the normal from central
// differences, the colour) on the voxel pool the device shares with the CPU, in the CPU's order
// of operations with multiply-adds kept apart (`precise`). The host computes the depth range of
// each 8x8 cell from the allocated blocks (TsdfVolume::depth_ranges) and uploads the hash table
// when it changed.
//
// The pool is bound as up to four windows (a binding reaches maxStorageBufferRange: lavapipe's is
// 128 MiB); a slot's window is slot / window_blocks. No NaN or infinity on the device: an empty
// range cell or search interval has far < near, a pixel without a hit depth 0.

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 0) readonly buffer Pool0 { uint pool0[]; };
layout(std430, set = 0, binding = 1) readonly buffer Pool1 { uint pool1[]; };
layout(std430, set = 0, binding = 2) readonly buffer Pool2 { uint pool2[]; };
layout(std430, set = 0, binding = 3) readonly buffer Pool3 { uint pool3[]; };
layout(std430, set = 0, binding = 4) readonly buffer Hash { ivec4 entries[]; }; // block xyz, slot (-1: empty)
layout(std430, set = 0, binding = 5) readonly buffer Ranges { vec2 ranges[]; }; // the cells', then (has_search) each pixel's search interval
layout(std430, set = 0, binding = 6) writeonly buffer Hits { float hits[]; }; // HIT_FLOATS per pixel
layout(std430, set = 0, binding = 7) readonly buffer Params {
	float fx, fy, cx, cy;
	int width, height, cells_x, has_search;
	vec4 rotation[3]; // world_from_camera, columns
	vec4 origin; // the camera centre, world metres
	vec4 bounds_min, bounds_max; // the allocated blocks, world metres
	float voxel_size, truncation, min_depth_m, max_depth_m;
	uint hash_mask, window_blocks, normals, search_offset; // search_offset: first vec2 of the pixels' intervals
} params;

const uint HIT_FLOATS = 12; // point xyz, depth, normal xyz, rgb, steps (float bits), 0

uint word_at(uint p_ref, uint p_word) {
	const uint slot = p_ref >> 9, window = slot / params.window_blocks;
	const uint i = ((slot - window * params.window_blocks) * 512u + (p_ref & 511u)) * 3u + p_word;
	if (window == 0u) {
		return pool0[i];
	}
	if (window == 1u) {
		return pool1[i];
	}
	if (window == 2u) {
		return pool2[i];
	}
	return pool3[i];
}

const uint NONE = 0xFFFFFFFFu;

// tsdf_find_slot with TsdfBlockCache: the last block looked up.
ivec3 cache_block = ivec3(-2147483647 - 1);
int cache_slot = -1;

int find_slot(ivec3 p_block) {
	if (p_block == cache_block) {
		return cache_slot;
	}
	cache_block = p_block;
	uint i = ((uint(p_block.x) * 73856093u) ^ (uint(p_block.y) * 19349669u) ^ (uint(p_block.z) * 83492791u)) & params.hash_mask;
	cache_slot = -1;
	for (uint probes = 0u; probes <= params.hash_mask; probes++) {
		const ivec4 e = entries[i];
		if (e.w == -1) {
			break;
		}
		if (e.xyz == p_block) {
			cache_slot = e.w;
			break;
		}
		i = (i + 1u) & params.hash_mask;
	}
	return cache_slot;
}

// tsdf_voxel_at: the voxel's reference (slot * 512 + local index), or NONE.
uint voxel_ref(ivec3 p_voxel) {
	const int slot = find_slot(p_voxel >> 3);
	if (slot < 0) {
		return NONE;
	}
	const ivec3 l = p_voxel & 7;
	return uint(slot) * 512u + uint(l.x + 8 * (l.y + 8 * l.z));
}

float tsdf_of(uint p_ref) {
	return uintBitsToFloat(word_at(p_ref, 0u));
}
uint weight_of(uint p_ref) {
	return word_at(p_ref, 1u) & 0xFFFFu;
}

int floor_int(float p_x) {
	const int i = int(p_x);
	return i - int(p_x < float(i));
}

float fmin_nan(float p_a, float p_b) {
	return (p_b < p_a || p_a != p_a) ? p_b : p_a;
}
float fmax_nan(float p_a, float p_b) {
	return (p_b > p_a || p_a != p_a) ? p_b : p_a;
}

// tsdf_cell_corners: the 8 corners' tsdf, false where any is unallocated or unobserved.
bool cell_corners(vec3 p_grid, out float r_corner[8], out vec3 r_frac) {
	const vec3 base_f = vec3(float(floor_int(p_grid.x)), float(floor_int(p_grid.y)), float(floor_int(p_grid.z)));
	const ivec3 base = ivec3(base_f);
	precise vec3 frac = p_grid - base_f;
	r_frac = frac;
	const ivec3 l = base & 7;
	if (l.x < 7 && l.y < 7 && l.z < 7) {
		const uint v0 = voxel_ref(base);
		if (v0 == NONE) {
			return false;
		}
		for (int c = 0; c < 8; c++) {
			const uint v = v0 + uint((c & 1) + 8 * (((c >> 1) & 1) + 8 * ((c >> 2) & 1)));
			if (weight_of(v) == 0u) {
				return false;
			}
			r_corner[c] = tsdf_of(v);
		}
		return true;
	}
	for (int c = 0; c < 8; c++) {
		const uint v = voxel_ref(base + ivec3(c & 1, (c >> 1) & 1, (c >> 2) & 1));
		if (v == NONE || weight_of(v) == 0u) {
			return false;
		}
		r_corner[c] = tsdf_of(v);
	}
	return true;
}

bool trilinear(vec3 p_grid, out float r_tsdf) {
	float c[8];
	vec3 f;
	r_tsdf = 0.0;
	if (!cell_corners(p_grid, c, f)) {
		return false;
	}
	precise float x00 = c[0] + (c[1] - c[0]) * f.x;
	precise float x10 = c[2] + (c[3] - c[2]) * f.x;
	precise float x01 = c[4] + (c[5] - c[4]) * f.x;
	precise float x11 = c[6] + (c[7] - c[6]) * f.x;
	precise float y0 = x00 + (x10 - x00) * f.y;
	precise float y1 = x01 + (x11 - x01) * f.y;
	precise float result = y0 + (y1 - y0) * f.z;
	r_tsdf = result;
	return true;
}

// tsdf_trilinear_color: over the corners that have a colour.
bool trilinear_color(vec3 p_grid, out vec3 r_rgb) {
	const vec3 base_f = vec3(float(floor_int(p_grid.x)), float(floor_int(p_grid.y)), float(floor_int(p_grid.z)));
	const ivec3 base = ivec3(base_f);
	precise vec3 f = p_grid - base_f;
	precise vec3 sum = vec3(0.0);
	precise float total = 0.0;
	for (int c = 0; c < 8; c++) {
		const ivec3 o = ivec3(c & 1, (c >> 1) & 1, (c >> 2) & 1);
		const uint v = voxel_ref(base + o);
		if (v == NONE || (word_at(v, 1u) >> 16) == 0u) {
			continue;
		}
		const uint rgb = word_at(v, 2u);
		precise float w = (o.x != 0 ? f.x : 1.0 - f.x) * (o.y != 0 ? f.y : 1.0 - f.y) * (o.z != 0 ? f.z : 1.0 - f.z);
		sum += w * vec3(float(rgb & 0xFFu), float((rgb >> 8) & 0xFFu), float((rgb >> 16) & 0xFFu));
		total += w;
	}
	r_rgb = vec3(0.0);
	if (!(total > 1e-6)) {
		return false;
	}
	precise vec3 mean = sum / total;
	r_rgb = mean;
	return true;
}

// tsdf_gradient: central differences, else the cell's own gradient.
bool gradient(vec3 p_grid, out vec3 r_gradient) {
	float fp[3], fm[3];
	bool ok = true;
	for (int a = 0; a < 3 && ok; a++) {
		vec3 d = vec3(0.0);
		d[a] = 1.0;
		precise vec3 ahead = p_grid + d, behind = p_grid - d;
		ok = trilinear(ahead, fp[a]) && trilinear(behind, fm[a]);
	}
	if (ok) {
		precise vec3 g = vec3(fp[0] - fm[0], fp[1] - fm[1], fp[2] - fm[2]);
		r_gradient = g;
		return true;
	}
	float c[8];
	vec3 f;
	r_gradient = vec3(0.0);
	if (!cell_corners(p_grid, c, f)) {
		return false;
	}
	precise vec3 g = vec3(0.0);
	for (int i = 0; i < 8; i++) {
		const ivec3 o = ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
		precise float wx = o.x != 0 ? f.x : 1.0 - f.x, wy = o.y != 0 ? f.y : 1.0 - f.y, wz = o.z != 0 ? f.z : 1.0 - f.z;
		const float s = c[i];
		g.x += s * (o.x != 0 ? 1.0 : -1.0) * wy * wz;
		g.y += s * (o.y != 0 ? 1.0 : -1.0) * wx * wz;
		g.z += s * (o.z != 0 ? 1.0 : -1.0) * wx * wy;
	}
	r_gradient = g;
	return true;
}

float refine_crossing(vec3 p_origin_grid, vec3 p_dir_grid, float p_ta, float p_fa, float p_tb, float p_fb) {
	precise float ta = p_ta, fa = p_fa, tb = p_tb, fb = p_fb;
	for (int i = 0; i < 3; i++) {
		precise float t = ta + (tb - ta) * fa / (fa - fb);
		precise vec3 g = p_origin_grid + t * p_dir_grid;
		float f;
		if (!trilinear(g, f)) {
			return t;
		}
		if (f > 0.0) {
			ta = t;
			fa = f;
		} else {
			tb = t;
			fb = f;
		}
	}
	precise float last = ta + (tb - ta) * fa / (fa - fb);
	return last;
}

vec3 rotate(vec3 p_v) {
	precise vec3 r = params.rotation[0].xyz * p_v.x + params.rotation[1].xyz * p_v.y + params.rotation[2].xyz * p_v.z;
	return r;
}

vec3 unit(vec3 p_v) { // glm::normalize: v * (1 / sqrt(dot(v, v)))
	precise float length2 = p_v.x * p_v.x + p_v.y * p_v.y + p_v.z * p_v.z;
	precise vec3 n = p_v * (1.0 / sqrt(length2));
	return n;
}

void main() {
	const int u = int(gl_GlobalInvocationID.x), v = int(gl_GlobalInvocationID.y);
	if (u >= params.width || v >= params.height) {
		return;
	}
	const uint pixel = uint(v * params.width + u);
	for (uint k = 0u; k < HIT_FLOATS; k++) {
		hits[pixel * HIT_FLOATS + k] = 0.0;
	}
	vec2 range = ranges[uint((v / 8) * params.cells_x + u / 8)];
	if (params.has_search != 0) {
		const vec2 search = ranges[params.search_offset + pixel];
		if (search.y >= search.x) {
			range = vec2(max(range.x, search.x), min(range.y, search.y));
		}
	}
	if (!(range.x <= range.y)) {
		return;
	}
	const float vs = params.voxel_size;
	precise float min_depth = max(params.min_depth_m, range.x), max_depth = min(params.max_depth_m, range.y);
	precise vec3 ray_camera = vec3((float(u) - params.cx) / params.fx * 1.0, (float(v) - params.cy) / params.fy * 1.0, 1.0);
	const vec3 dir_camera = unit(ray_camera);
	const vec3 dir = rotate(dir_camera);
	precise float inv_vs = 1.0 / vs;
	const vec3 origin = params.origin.xyz;
	precise vec3 origin_grid = origin * inv_vs;
	precise vec3 dir_grid = dir * inv_vs;
	precise vec3 inv_dir = vec3(1.0 / dir.x, 1.0 / dir.y, 1.0 / dir.z);
	precise float t = min_depth / dir_camera.z;
	precise float t_end = max_depth / dir_camera.z;
	{ // tsdf_clip_to_box
		precise vec3 t0 = (params.bounds_min.xyz - origin) * inv_dir;
		precise vec3 t1 = (params.bounds_max.xyz - origin) * inv_dir;
		const vec3 tnear = min(t0, t1), tfar = max(t0, t1);
		t = fmax_nan(t, fmax_nan(tnear.x, fmax_nan(tnear.y, tnear.z)));
		t_end = fmin_nan(t_end, fmin_nan(tfar.x, fmin_nan(tfar.y, tfar.z)));
		if (!(t <= t_end)) {
			return;
		}
	}
	precise float block_m = vs * 8.0;
	precise float fine_step = 0.5 * vs;
	bool have_prev = false;
	float t_prev = 0.0, f_prev = 0.0;
	uint steps = 0u;
	while (t <= t_end && steps < 1000000u) { // the guard: a ray crosses at most a few thousand samples
		steps++;
		precise vec3 g = origin_grid + t * dir_grid;
		precise vec3 g_half = g + 0.5;
		const ivec3 voxel = ivec3(floor_int(g_half.x), floor_int(g_half.y), floor_int(g_half.z));
		const uint nearest = voxel_ref(voxel);
		if (cache_slot < 0) {
			precise vec3 bmin = (vec3(cache_block) * 8.0 - vec3(0.5)) * vs;
			precise vec3 bmax = bmin + vec3(block_m);
			precise vec3 e0 = (bmin - origin) * inv_dir;
			precise vec3 e1 = (bmax - origin) * inv_dir;
			const vec3 efar = max(e0, e1);
			const float exit_t = fmin_nan(efar.x, fmin_nan(efar.y, efar.z));
			precise float next = fmax_nan(exit_t, t) + 1e-3 * vs;
			t = next;
			have_prev = false;
			continue;
		}
		if (weight_of(nearest) == 0u) {
			have_prev = false;
			t += fine_step;
			continue;
		}
		float f = tsdf_of(nearest);
		precise float reach = abs(f) * params.truncation;
		if (reach < 2.0 * vs) {
			float fine;
			if (trilinear(g, fine)) {
				f = fine;
			}
		}
		if (have_prev && f_prev > 0.0 && f <= 0.0) {
			const float ts = refine_crossing(origin_grid, dir_grid, t_prev, f_prev, t, f);
			precise vec3 gs = origin_grid + ts * dir_grid;
			vec3 n = vec3(0.0);
			if (params.normals != 0u) {
				vec3 gr;
				if (!gradient(gs, gr) || !(gr.x * gr.x + gr.y * gr.y + gr.z * gr.z > 0.0)) {
					hits[pixel * HIT_FLOATS + 10u] = uintBitsToFloat(steps);
					return;
				}
				n = unit(gr);
				precise float facing = n.x * dir.x + n.y * dir.y + n.z * dir.z;
				if (facing > 0.0) {
					n = -n;
				}
			}
			precise vec3 point = origin + ts * dir;
			precise float depth = ts * dir_camera.z;
			vec3 rgb;
			trilinear_color(gs, rgb); // 0 where no corner has a colour
			const uint o = pixel * HIT_FLOATS;
			hits[o] = point.x;
			hits[o + 1u] = point.y;
			hits[o + 2u] = point.z;
			hits[o + 3u] = depth;
			hits[o + 4u] = n.x;
			hits[o + 5u] = n.y;
			hits[o + 6u] = n.z;
			hits[o + 7u] = rgb.x;
			hits[o + 8u] = rgb.y;
			hits[o + 9u] = rgb.z;
			hits[o + 10u] = uintBitsToFloat(steps);
			return;
		}
		have_prev = true;
		t_prev = t;
		f_prev = f;
		precise float sphere = 0.8 * f * params.truncation;
		t += f > 0.0 ? max(fine_step, sphere) : fine_step;
	}
	hits[pixel * HIT_FLOATS + 10u] = uintBitsToFloat(steps);
}
