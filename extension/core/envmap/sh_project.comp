#version 450
// SH projection's rows on the GPU (envmap/spherical_harmonics.h, ShProjectorGpu): one invocation
// per face row sums its texels' radiance x y_i dOmega in float, in texel order, as project_sh does
// a row; the host adds the rows in double.

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Faces { float faces[]; }; // [face][v][u] R, G, B
layout(std430, set = 0, binding = 1) readonly buffer Weights { float weights[]; }; // [face][v][u][25]
layout(std430, set = 0, binding = 2) writeonly buffer Rows { float rows[]; }; // [row][channel][25]

layout(push_constant) uniform Push {
	uint size; // face size, texels
} push;

void main() {
	const uint row = gl_GlobalInvocationID.x;
	if (row >= 6u * push.size) {
		return;
	}
	float sum[75];
	for (uint i = 0u; i < 75u; i++) {
		sum[i] = 0.0;
	}
	for (uint u = 0u; u < push.size; u++) {
		const uint texel = row * push.size + u;
		const vec3 radiance = vec3(faces[3u * texel], faces[3u * texel + 1u], faces[3u * texel + 2u]);
		for (uint i = 0u; i < 25u; i++) {
			const float w = weights[25u * texel + i];
			sum[i] += radiance.x * w;
			sum[25u + i] += radiance.y * w;
			sum[50u + i] += radiance.z * w;
		}
	}
	for (uint i = 0u; i < 75u; i++) {
		rows[75u * row + i] = sum[i];
	}
}
