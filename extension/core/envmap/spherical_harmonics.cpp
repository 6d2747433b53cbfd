#include "spherical_harmonics.h"

#include <glm/geometric.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace roomprobe {

namespace {

// K_l^m for |m|, times sqrt(2) when m != 0, for l < SH_BANDS.
struct ShNormalisation {
	double k[SH_BANDS][SH_BANDS] = {};
	ShNormalisation() {
		for (int l = 0; l < SH_BANDS; l++) {
			for (int m = 0; m <= l; m++) {
				double ratio = 1.0; // (l - m)! / (l + m)!
				for (int f = l - m + 1; f <= l + m; f++) {
					ratio /= double(f);
				}
				k[l][m] = std::sqrt((2.0 * l + 1.0) / (4.0 * std::numbers::pi) * ratio) * (m == 0 ? 1.0 : std::numbers::sqrt2);
			}
		}
	}
};

const ShNormalisation &normalisation() {
	static const ShNormalisation table;
	return table;
}

} // namespace

std::array<double, SH_COEFFICIENTS> sh_basis(const glm::dvec3 &p_direction) {
	const glm::dvec3 d = glm::normalize(p_direction);
	const ShNormalisation &norm = normalisation();
	std::array<double, SH_COEFFICIENTS> values{};
	// Re and Im of (x + i y)^m = sin^m(theta) e^{i m phi}.
	double re = 1.0;
	double im = 0.0;
	// Q_m^m = (-1)^m (2m - 1)!!: P_l^m(z) / sin^m(theta), the polynomial part.
	double q_mm = 1.0;
	for (int m = 0; m < SH_BANDS; m++) {
		if (m > 0) {
			const double next_re = re * d.x - im * d.y;
			im = re * d.y + im * d.x;
			re = next_re;
			q_mm *= -(2.0 * m - 1.0);
		}
		double q_prev = 0.0; // Q_{l-2}^m
		double q = q_mm; // Q_{l-1}^m, starting at l = m
		for (int l = m; l < SH_BANDS; l++) {
			if (l == m + 1) {
				q_prev = q;
				q = d.z * (2.0 * m + 1.0) * q_prev;
			} else if (l > m + 1) {
				const double next = ((2.0 * l - 1.0) * d.z * q - (l + m - 1.0) * q_prev) / double(l - m);
				q_prev = q;
				q = next;
			}
			const double base = norm.k[l][m] * q;
			if (m == 0) {
				values[size_t(sh_index(l, 0))] = base;
			} else {
				values[size_t(sh_index(l, m))] = base * re;
				values[size_t(sh_index(l, -m))] = base * im;
			}
		}
	}
	return values;
}

ShCoefficients project_sh(const Cubemap &p_cubemap) {
	ShCoefficients total;
	total.fill(glm::dvec3(0.0));
	if (!is_valid_cubemap(p_cubemap)) {
		return total;
	}
	const int n = p_cubemap.size;
	std::vector<double> solid_angles(size_t(n) * size_t(n));
	for (int v = 0; v < n; v++) {
		for (int u = 0; u < n; u++) {
			solid_angles[size_t(v) * size_t(n) + size_t(u)] = cubemap_texel_solid_angle(u, v, n);
		}
	}
	std::vector<ShCoefficients> rows(size_t(6 * n));
	tbb::parallel_for(tbb::blocked_range<int>(0, 6 * n), [&](const tbb::blocked_range<int> &p_rows) {
		for (int row = p_rows.begin(); row != p_rows.end(); row++) {
			const int face = row / n;
			const int v = row % n;
			ShCoefficients &sum = rows[size_t(row)];
			sum.fill(glm::dvec3(0.0));
			const cv::Vec3f *pixels = p_cubemap.faces[size_t(face)].ptr<cv::Vec3f>(v);
			for (int u = 0; u < n; u++) {
				const std::array<double, SH_COEFFICIENTS> y = sh_basis(cubemap_direction(face, u, v, n));
				const double weight = solid_angles[size_t(v) * size_t(n) + size_t(u)];
				const glm::dvec3 value = glm::dvec3(pixels[u][0], pixels[u][1], pixels[u][2]) * weight;
				for (int i = 0; i < SH_COEFFICIENTS; i++) {
					sum[size_t(i)] += value * y[size_t(i)];
				}
			}
		}
	});
	for (const ShCoefficients &row : rows) {
		for (int i = 0; i < SH_COEFFICIENTS; i++) {
			total[size_t(i)] += row[size_t(i)];
		}
	}
	return total;
}

glm::dvec3 evaluate_sh(const ShCoefficients &p_coefficients, const glm::dvec3 &p_direction) {
	const std::array<double, SH_COEFFICIENTS> y = sh_basis(p_direction);
	glm::dvec3 value(0.0);
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		value += p_coefficients[size_t(i)] * y[size_t(i)];
	}
	return value;
}

double sh_cosine_lobe_factor(int p_l) {
	constexpr double pi = std::numbers::pi;
	switch (p_l) {
		case 0:
			return pi;
		case 1:
			return 2.0 * pi / 3.0;
		case 2:
			return pi / 4.0;
		case 4:
			return -pi / 24.0;
		default:
			return 0.0; // odd bands beyond 1 vanish
	}
}

ShCoefficients convolve_cosine_lobe(const ShCoefficients &p_radiance) {
	ShCoefficients irradiance;
	for (int l = 0; l < SH_BANDS; l++) {
		const double a = sh_cosine_lobe_factor(l);
		for (int m = -l; m <= l; m++) {
			irradiance[size_t(sh_index(l, m))] = p_radiance[size_t(sh_index(l, m))] * a;
		}
	}
	return irradiance;
}

} // namespace roomprobe
