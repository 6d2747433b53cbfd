#version 450
// One pyramid level from the one above on the GPU (downsample_depth_pixel in slam/icp_kernels.h,
// and the intensity's 2x2 mean, as cv::resize INTER_AREA at half size gives it), for
// IcpReducerGpu::build_frame. Depth 0 = no reading.

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 0) buffer Depth { float depth[]; };
layout(std430, set = 0, binding = 1) buffer Intensity { float intensity[]; };

layout(push_constant) uniform Push {
	uint in_width, in_height, in_offset; // the level above: pixels, first float
	uint out_width, out_height, out_offset; // this level
	uint intensity_in_offset, intensity_out_offset; // first floats in Intensity
	uint has_intensity; // 0 / 1
	float band_m; // blocks average the depths within this of their nearest, metres
} push;

void main() {
	const uint x = gl_GlobalInvocationID.x, y = gl_GlobalInvocationID.y;
	if (x >= push.out_width || y >= push.out_height) {
		return;
	}
	float values[4];
	int count = 0;
	float nearest = 1.0e30;
	for (uint dy = 0u; dy < 2u; dy++) {
		for (uint dx = 0u; dx < 2u; dx++) {
			const uint sx = 2u * x + dx, sy = 2u * y + dy;
			if (sx >= push.in_width || sy >= push.in_height) {
				continue;
			}
			const float d = depth[push.in_offset + sy * push.in_width + sx];
			if (d > 0.0) {
				values[count++] = d;
				nearest = min(d, nearest);
			}
		}
	}
	float result = 0.0;
	if (count > 0) {
		float sum = 0.0;
		int used = 0;
		for (int i = 0; i < count; i++) {
			if (values[i] - nearest <= push.band_m) {
				sum += values[i];
				used++;
			}
		}
		result = sum / float(used);
	}
	depth[push.out_offset + y * push.out_width + x] = result;
	if (push.has_intensity != 0u) {
		const uint top = push.intensity_in_offset + 2u * y * push.in_width + 2u * x;
		const uint bottom = top + push.in_width;
		intensity[push.intensity_out_offset + y * push.out_width + x] =
				(intensity[top] + intensity[top + 1u] + intensity[bottom] + intensity[bottom + 1u]) * 0.25;
	}
}
