#version 450
// The coarse cubemap's gather on the GPU (envmap/coarse_render.h, CoarseGatherGpu): per cubemap
// texel, the atlas at its four taps as the first tap plus the others' weighted differences from
// it, in CoarseCubemapRenderer::gather's order and without contraction into fused multiply-adds
// (precise), so that the faces are the CPU's to the bit.

layout(local_size_x = 64) in;

struct Taps {
	uint index[4]; // atlas texels, row-major
	float hit; // 0: the ray hit nothing (black)
	float weight[3]; // of taps 1..3
};

layout(std430, set = 0, binding = 0) readonly buffer TapsBuffer { Taps taps[]; }; // [face][v][u]
layout(std430, set = 0, binding = 1) readonly buffer Atlas { float atlas[]; }; // [y][x][channel]
layout(std430, set = 0, binding = 2) writeonly buffer Faces { float faces[]; }; // [face][v][u][channel]

layout(push_constant) uniform Push {
	uint texels; // 6 size^2
	uint channels; // 1 or 3
} push;

void main() {
	const uint t = gl_GlobalInvocationID.x;
	if (t >= push.texels) {
		return;
	}
	const Taps tap = taps[t];
	const uint n = push.channels;
	for (uint k = 0u; k < n; k++) {
		precise float value = 0.0;
		if (tap.hit != 0.0) {
			const float c0 = atlas[n * tap.index[0] + k];
			const float c1 = atlas[n * tap.index[1] + k];
			const float c2 = atlas[n * tap.index[2] + k];
			const float c3 = atlas[n * tap.index[3] + k];
			value = c0 + tap.weight[0] * (c1 - c0) + tap.weight[1] * (c2 - c0) + tap.weight[2] * (c3 - c0);
		}
		faces[n * t + k] = value;
	}
}
