#version 450
// The finest level's edge-preserving smoothing on the GPU (smooth_depth_pixel in
// slam/icp_kernels.h, for IcpReducerGpu::build_frame): the window's taps within the band of the
// centre, weighted, in the CPU's order (row by row, left to right). Depth 0 = no reading (the
// host turns NaN into 0: a driver may assume no NaN).

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 0) readonly buffer Weights { float weights[]; }; // (2 radius + 1)^2, row by row
layout(std430, set = 0, binding = 1) buffer Depth { float depth[]; }; // every level, at the offsets below

layout(push_constant) uniform Push {
	uint width, height; // pixels
	uint in_offset, out_offset; // first float of the clean depth and of the smoothed one
	int radius; // pixels
	float band_m; // metres
} push;

void main() {
	const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
	const int w = int(push.width), h = int(push.height);
	if (x >= w || y >= h) {
		return;
	}
	const float centre = depth[push.in_offset + uint(y * w + x)];
	float result = 0.0;
	if (centre > 0.0) {
		const int side = 2 * push.radius + 1;
		float sum = 0.0, weight_sum = 0.0;
		for (int dy = -push.radius; dy <= push.radius; dy++) {
			const int ty = y + dy;
			if (ty < 0 || ty >= h) {
				continue;
			}
			for (int dx = -push.radius; dx <= push.radius; dx++) {
				const int tx = x + dx;
				if (tx < 0 || tx >= w) {
					continue;
				}
				const float d = depth[push.in_offset + uint(ty * w + tx)];
				if (d > 0.0 && abs(d - centre) <= push.band_m) {
					const float weight = weights[(dy + push.radius) * side + dx + push.radius];
					sum += weight * d;
					weight_sum += weight;
				}
			}
		}
		result = sum / weight_sum;
	}
	depth[push.out_offset + uint(y * w + x)] = result;
}
