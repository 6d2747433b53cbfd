#version 450
// The slope factor of every depth pixel on the GPU (tsdf_depth_slope in slam/tsdf_kernels.h, for
// TsdfIntegratorGpu): -n . x / z of the surface's tangent plane, n from central differences of
// the neighbouring readings (one-sided at a missing or far neighbour), in the CPU's order of
// operations with multiply-adds kept apart. Depth 0 = no reading; the factor is -1 where the CPU's
// is NaN (no tangent plane).

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, set = 0, binding = 0) buffer Frame { float frame[]; }; // the depth at depth_offset, the factors written at slope_offset

layout(push_constant) uniform Push {
	float fx, fy, cx, cy;
	int width, height;
	uint depth_offset, slope_offset;
	float max_jump_m;
} push;

float depth_at(int p_u, int p_v) {
	return frame[push.depth_offset + uint(p_v * push.width + p_u)];
}

vec3 unproject(int p_u, int p_v, float p_z) {
	precise vec3 x = vec3((float(p_u) - push.cx) / push.fx * p_z, (float(p_v) - push.cy) / push.fy * p_z, p_z);
	return x;
}

// The point of neighbour (u + du, v + dv), or false when it is not usable.
bool neighbour(int p_u, int p_v, float p_d, int p_du, int p_dv, out vec3 r_point) {
	const int u = p_u + p_du, v = p_v + p_dv;
	r_point = vec3(0.0);
	if (u < 0 || v < 0 || u >= push.width || v >= push.height) {
		return false;
	}
	const float dn = depth_at(u, v);
	precise float jump = abs(dn - p_d);
	if (!(dn > 0.0) || !(jump < push.max_jump_m)) {
		return false;
	}
	r_point = unproject(u, v, dn);
	return true;
}

bool tangent(int p_u, int p_v, float p_d, vec3 p_x, int p_du, int p_dv, out vec3 r_tangent) {
	vec3 a, b;
	const bool has_a = neighbour(p_u, p_v, p_d, -p_du, -p_dv, a), has_b = neighbour(p_u, p_v, p_d, p_du, p_dv, b);
	precise vec3 t = vec3(0.0);
	if (has_a && has_b) {
		t = b - a;
	} else if (has_b) {
		t = b - p_x;
	} else if (has_a) {
		t = p_x - a;
	} else {
		r_tangent = t;
		return false;
	}
	r_tangent = t;
	return true;
}

void main() {
	const int u = int(gl_GlobalInvocationID.x), v = int(gl_GlobalInvocationID.y);
	if (u >= push.width || v >= push.height) {
		return;
	}
	float slope = -1.0;
	const float d = depth_at(u, v);
	if (d > 0.0) {
		const vec3 x = unproject(u, v, d);
		vec3 tx, ty;
		if (tangent(u, v, d, x, 1, 0, tx) && tangent(u, v, d, x, 0, 1, ty)) {
			// glm::cross, glm::length and glm::dot, term by term
			precise vec3 n = vec3(tx.y * ty.z - ty.y * tx.z, tx.z * ty.x - ty.z * tx.x, tx.x * ty.y - ty.x * tx.y);
			precise float length2 = n.x * n.x + n.y * n.y + n.z * n.z;
			precise float len = sqrt(length2);
			if (len > 0.0) {
				precise float along = n.x * x.x + n.y * x.y + n.z * x.z;
				precise float factor = abs(along) / (len * x.z);
				slope = factor;
			}
		}
	}
	frame[push.slope_offset + uint(v * push.width + u)] = slope;
}
