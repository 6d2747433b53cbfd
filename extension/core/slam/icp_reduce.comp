#version 450
// ICP's normal equations on the GPU (slam/icp_reduce_gpu.h): one workgroup per sampled image row
// pairs the row's pixels with the model as icp_correspondence (slam/icp_kernels.h) does, each
// invocation sums its pixels' rows in float, and the workgroup adds the 64 partial sums in a
// tree; the host adds the rows in double, in row order, as the CPU's accumulate does.
// The host packs validity as flags (no NaN reaches the kernel: a driver may assume none).

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Params {
	vec4 rotation[3]; // world_from_camera, the estimate: columns
	vec4 translation; // metres
	vec4 model_rotation[3]; // the model's camera_from_world: columns
	vec4 model_translation; // metres
	vec4 camera; // the model's fx, fy, cx, cy (pixels)
	ivec4 model_size; // width, height, has colour (0/1), 0
	ivec4 frame; // sampled columns, sampled rows, first float of the level, 0
	vec4 thresholds; // max distance (m), min normal cos, colour weight (m per unit intensity), max colour difference
	vec4 noise; // a (m), b (per m^2), c (m), reference sigma (m)
} p;
// Per sampled pixel, 8 floats: vertex x, y, z (camera frame, m), normal x, y, z, intensity, flags
// (1: vertex and normal valid, 2: intensity valid).
layout(std430, set = 0, binding = 1) readonly buffer Frame { float frame[]; };
// Per model pixel, 12 floats: point x, y, z (world, m), 1 if point and normal are valid; normal
// x, y, z, 0; intensity, gradient x, gradient y (per pixel), 1 if all three are valid.
layout(std430, set = 0, binding = 2) readonly buffer Model { float model[]; };
// Per sampled row, 32 floats: J^T J's upper triangle (21), J^T r (6), the traces of the rotation
// and translation blocks of the point-to-plane rows, the sum of squared point-to-plane residuals,
// the inlier count, 0.
layout(std430, set = 0, binding = 3) writeonly buffer Rows { float rows[]; };

const uint SUMS = 32u;
shared float partial[SUMS][64];

float sums[SUMS];

void add_row(float j[6], float r) {
	uint k = 0u;
	for (int a = 0; a < 6; a++) {
		for (int b = a; b < 6; b++) {
			sums[k++] += j[a] * j[b];
		}
		sums[21 + a] += j[a] * r;
	}
}

float noise_weight(float z) {
	const float d = z - p.noise.z;
	const float sigma = p.noise.x + p.noise.y * d * d;
	return sigma > p.noise.w ? p.noise.w / sigma : 1.0;
}

// Bilinear sample of one of the model's colour floats (channel 8, 9 or 10) at p_base's four
// neighbours with weights ax, ay.
float bilinear(uint base00, uint base10, uint base01, uint base11, uint channel, float ax, float ay) {
	return (1.0 - ay) * ((1.0 - ax) * model[base00 + channel] + ax * model[base10 + channel]) +
			ay * ((1.0 - ax) * model[base01 + channel] + ax * model[base11 + channel]);
}

// One pixel's rows, added to sums.
void correspond(vec3 v, vec3 n, float intensity, bool has_intensity) {
	const mat3 rotation = mat3(p.rotation[0].xyz, p.rotation[1].xyz, p.rotation[2].xyz);
	const mat3 model_rotation = mat3(p.model_rotation[0].xyz, p.model_rotation[1].xyz, p.model_rotation[2].xyz);
	const vec3 offset = rotation * v;
	const vec3 point = offset + p.translation.xyz;
	const vec3 normal = rotation * n;
	const vec3 q = model_rotation * point + p.model_translation.xyz;
	if (!(q.z > 0.0)) {
		return;
	}
	const vec2 pixel = vec2(p.camera.x * q.x / q.z + p.camera.z, p.camera.y * q.y / q.z + p.camera.w);
	const float sx = pixel.x + 0.5, sy = pixel.y + 0.5;
	const int w = p.model_size.x, h = p.model_size.y;
	if (!(sx > 0.0 && sy > 0.0 && sx < float(w) && sy < float(h))) {
		return;
	}
	const uint base = 12u * uint(int(sy) * w + int(sx));
	if (model[base + 3u] == 0.0) {
		return;
	}
	const vec3 model_point = vec3(model[base], model[base + 1u], model[base + 2u]);
	const vec3 model_normal = vec3(model[base + 4u], model[base + 5u], model[base + 6u]);
	const vec3 difference = point - model_point;
	if (dot(difference, difference) > p.thresholds.x * p.thresholds.x || dot(normal, model_normal) < p.thresholds.y) {
		return;
	}
	const float weight = noise_weight(v.z);
	const float residual = dot(model_normal, difference);
	const vec3 moment = cross(offset, model_normal) * weight;
	const vec3 weighted_normal = model_normal * weight;
	const float j[6] = float[6](moment.x, moment.y, moment.z, weighted_normal.x, weighted_normal.y, weighted_normal.z);
	add_row(j, residual * weight);
	sums[27] += j[0] * j[0] + j[1] * j[1] + j[2] * j[2];
	sums[28] += j[3] * j[3] + j[4] * j[4] + j[5] * j[5];
	sums[29] += residual * residual;
	sums[30] += 1.0;
	const float colour_weight = p.thresholds.z;
	if (p.model_size.z == 0 || colour_weight == 0.0 || !has_intensity) {
		return;
	}
	const int x0 = int(floor(pixel.x)), y0 = int(floor(pixel.y));
	if (x0 < 0 || y0 < 0 || x0 + 1 >= w || y0 + 1 >= h) {
		return;
	}
	const uint b00 = 12u * uint(y0 * w + x0), b10 = b00 + 12u, b01 = b00 + 12u * uint(w), b11 = b01 + 12u;
	if (model[b00 + 11u] == 0.0 || model[b10 + 11u] == 0.0 || model[b01 + 11u] == 0.0 || model[b11 + 11u] == 0.0) {
		return;
	}
	const float ax = pixel.x - float(x0), ay = pixel.y - float(y0);
	const float model_intensity = bilinear(b00, b10, b01, b11, 8u, ax, ay);
	const float gx = bilinear(b00, b10, b01, b11, 9u, ax, ay);
	const float gy = bilinear(b00, b10, b01, b11, 10u, ax, ay);
	if (abs(model_intensity - intensity) > p.thresholds.w) {
		return;
	}
	const float inv_z = 1.0 / q.z;
	const vec3 dq = vec3(p.camera.x * gx * inv_z, p.camera.y * gy * inv_z, -(p.camera.x * gx * q.x + p.camera.y * gy * q.y) * inv_z * inv_z);
	const vec3 a = transpose(model_rotation) * dq * (colour_weight * weight);
	const vec3 colour_moment = cross(offset, a);
	const float jc[6] = float[6](colour_moment.x, colour_moment.y, colour_moment.z, a.x, a.y, a.z);
	add_row(jc, colour_weight * weight * (model_intensity - intensity));
}

void main() {
	const uint row = gl_WorkGroupID.x;
	const uint lane = gl_LocalInvocationID.x;
	for (uint k = 0u; k < SUMS; k++) {
		sums[k] = 0.0;
	}
	const uint cols = uint(p.frame.x);
	for (uint x = lane; x < cols; x += 64u) {
		const uint base = uint(p.frame.z) + 8u * (row * cols + x);
		const float flags = frame[base + 7u];
		if (flags == 1.0 || flags == 3.0) {
			correspond(vec3(frame[base], frame[base + 1u], frame[base + 2u]), vec3(frame[base + 3u], frame[base + 4u], frame[base + 5u]),
					frame[base + 6u], flags == 3.0);
		}
	}
	for (uint k = 0u; k < SUMS; k++) {
		partial[k][lane] = sums[k];
	}
	barrier();
	for (uint half_width = 32u; half_width > 0u; half_width >>= 1u) {
		if (lane < half_width) {
			for (uint k = 0u; k < SUMS; k++) {
				partial[k][lane] += partial[k][lane + half_width];
			}
		}
		barrier();
	}
	if (lane == 0u) {
		for (uint k = 0u; k < SUMS; k++) {
			rows[SUMS * row + k] = partial[k][0];
		}
	}
}
