#version 450
// The GGX prefilter's gather on the GPU (envmap/ggx_prefilter.h, GgxFilterGpu): an output texel is
// the weighted sum of its taps into the box pyramid, summed in tap order in float, as the CPU does.
// One invocation per output texel of one mip level (faces, rows, columns flattened).

layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer Pyramid { float pyramid[]; }; // R, G, B per texel
layout(std430, set = 0, binding = 1) readonly buffer First { uint first[]; }; // per output texel, and one past the end
layout(std430, set = 0, binding = 2) readonly buffer Texel { uint texel[]; }; // per tap: a pyramid texel
layout(std430, set = 0, binding = 3) readonly buffer Weight { float weight[]; }; // per tap
layout(std430, set = 0, binding = 4) writeonly buffer Result { float result[]; }; // R, G, B per output texel

layout(push_constant) uniform Push {
	uint texels; // output texels of the level
} push;

void main() {
	const uint i = gl_GlobalInvocationID.x;
	if (i >= push.texels) {
		return;
	}
	vec3 sum = vec3(0.0);
	for (uint k = first[i]; k < first[i + 1u]; k++) {
		const uint t = 3u * texel[k];
		sum += vec3(pyramid[t], pyramid[t + 1u], pyramid[t + 2u]) * weight[k];
	}
	result[3u * i] = sum.x;
	result[3u * i + 1u] = sum.y;
	result[3u * i + 2u] = sum.z;
}
