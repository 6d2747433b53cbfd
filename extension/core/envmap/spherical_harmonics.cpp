#include "spherical_harmonics.h"

#include <glm/geometric.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <map>
#include <memory>
#include <mutex>
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

namespace {

// y_i(d) dOmega of every texel of a cubemap of one face size, as floats: [face][v][u][i]. Built
// once per size, since the directions and solid angles never change.
struct ShTexelTable {
	int size = 0;
	std::vector<float> weights;
};

std::shared_ptr<const ShTexelTable> sh_texel_table(int p_size) {
	static std::mutex mutex;
	static std::map<int, std::shared_ptr<const ShTexelTable>> tables;
	const std::lock_guard<std::mutex> lock(mutex);
	std::shared_ptr<const ShTexelTable> &slot = tables[p_size];
	if (!slot) {
		auto table = std::make_shared<ShTexelTable>();
		table->size = p_size;
		const size_t n = size_t(p_size);
		table->weights.resize(6 * n * n * SH_COEFFICIENTS);
		for (int face = 0; face < 6; face++) {
			for (int v = 0; v < p_size; v++) {
				for (int u = 0; u < p_size; u++) {
					const std::array<double, SH_COEFFICIENTS> y = sh_basis(cubemap_direction(face, u, v, p_size));
					const double solid_angle = cubemap_texel_solid_angle(u, v, p_size);
					float *out = &table->weights[((size_t(face) * n + size_t(v)) * n + size_t(u)) * SH_COEFFICIENTS];
					for (int i = 0; i < SH_COEFFICIENTS; i++) {
						out[i] = float(y[size_t(i)] * solid_angle);
					}
				}
			}
		}
		slot = std::move(table);
	}
	return slot;
}

} // namespace

std::shared_ptr<const std::vector<float>> sh_texel_weights(int p_size) {
	const std::shared_ptr<const ShTexelTable> table = sh_texel_table(p_size);
	return std::shared_ptr<const std::vector<float>>(table, &table->weights);
}

std::array<cv::Mat, 6> sh_projection_faces(const Cubemap &p_cubemap, int p_max_face_size) {
	// Five bands vary over tens of degrees: box-filtering the faces down first changes the
	// coefficients by the texel-centre quadrature error of the smaller size (a few 1e-4 at 64^2),
	// and costs a sixteenth of the products at 256^2.
	if (p_max_face_size <= 0 || p_cubemap.size <= p_max_face_size) {
		return p_cubemap.faces;
	}
	std::array<cv::Mat, 6> small;
	for (int f = 0; f < 6; f++) {
		cv::resize(p_cubemap.faces[size_t(f)], small[size_t(f)], cv::Size(p_max_face_size, p_max_face_size), 0.0, 0.0, cv::INTER_AREA);
	}
	return small;
}

ShCoefficients project_sh(const Cubemap &p_cubemap, int p_max_face_size) {
	ShCoefficients total;
	total.fill(glm::dvec3(0.0));
	if (!is_valid_cubemap(p_cubemap)) {
		return total;
	}
	const std::array<cv::Mat, 6> small = sh_projection_faces(p_cubemap, p_max_face_size);
	const std::array<cv::Mat, 6> *faces = &small;
	const int n = small[0].cols;
	const std::shared_ptr<const ShTexelTable> table = sh_texel_table(n);
	std::vector<ShCoefficients> rows(size_t(6 * n));
	tbb::parallel_for(tbb::blocked_range<int>(0, 6 * n), [&](const tbb::blocked_range<int> &p_rows) {
		for (int row = p_rows.begin(); row != p_rows.end(); row++) {
			const int face = row / n;
			const int v = row % n;
			// A row in float (n texels), then added in double: the sums stay exact to 1e-6.
			std::array<float, 3 * SH_COEFFICIENTS> sum{};
			const cv::Vec3f *pixels = (*faces)[size_t(face)].ptr<cv::Vec3f>(v);
			const float *w = &table->weights[size_t(row) * size_t(n) * SH_COEFFICIENTS];
			for (int u = 0; u < n; u++, w += SH_COEFFICIENTS) {
				const cv::Vec3f &p = pixels[u];
				for (int i = 0; i < SH_COEFFICIENTS; i++) {
					sum[size_t(i)] += p[0] * w[i];
					sum[size_t(SH_COEFFICIENTS + i)] += p[1] * w[i];
					sum[size_t(2 * SH_COEFFICIENTS + i)] += p[2] * w[i];
				}
			}
			ShCoefficients &out = rows[size_t(row)];
			for (int i = 0; i < SH_COEFFICIENTS; i++) {
				out[size_t(i)] = glm::dvec3(sum[size_t(i)], sum[size_t(SH_COEFFICIENTS + i)], sum[size_t(2 * SH_COEFFICIENTS + i)]);
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

namespace {

// Per band l: 2 (2l + 1) fixed directions spread over the sphere (a Fibonacci spiral), and the
// least-squares inverse of the band's basis at them, computed once.
struct ShRotationTables {
	std::array<std::vector<glm::dvec3>, SH_BANDS> directions;
	std::array<cv::Mat, SH_BANDS> inverse; // (2l + 1) x directions
};

const ShRotationTables &rotation_tables() {
	static const ShRotationTables tables = [] {
		ShRotationTables t;
		for (int l = 0; l < SH_BANDS; l++) {
			const int count = 2 * (2 * l + 1);
			cv::Mat basis(count, 2 * l + 1, CV_64F);
			for (int i = 0; i < count; i++) {
				const double z = 1.0 - (2.0 * i + 1.0) / count;
				const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
				const double phi = 2.39996322972865332 * (i + 0.5 * l); // the golden angle, offset per band
				t.directions[size_t(l)].emplace_back(r * std::cos(phi), r * std::sin(phi), z);
				const auto y = sh_basis(t.directions[size_t(l)].back());
				for (int m = -l; m <= l; m++) {
					basis.at<double>(i, m + l) = y[size_t(sh_index(l, m))];
				}
			}
			cv::invert(basis, t.inverse[size_t(l)], cv::DECOMP_SVD);
		}
		return t;
	}();
	return tables;
}

} // namespace

ShCoefficients rotate_sh(const ShCoefficients &p_coefficients, const glm::dmat3 &p_rotation) {
	const ShRotationTables &tables = rotation_tables();
	ShCoefficients out{};
	for (int l = 0; l < SH_BANDS; l++) {
		const std::vector<glm::dvec3> &directions = tables.directions[size_t(l)];
		const cv::Mat &inverse = tables.inverse[size_t(l)];
		// The band's part of f at the rotated directions, then back to coefficients.
		std::vector<glm::dvec3> values(directions.size(), glm::dvec3(0.0));
		for (size_t i = 0; i < directions.size(); i++) {
			const auto y = sh_basis(p_rotation * directions[i]);
			for (int m = -l; m <= l; m++) {
				values[i] += p_coefficients[size_t(sh_index(l, m))] * y[size_t(sh_index(l, m))];
			}
		}
		for (int m = -l; m <= l; m++) {
			glm::dvec3 c(0.0);
			for (size_t i = 0; i < directions.size(); i++) {
				c += inverse.at<double>(m + l, int(i)) * values[i];
			}
			out[size_t(sh_index(l, m))] = c;
		}
	}
	return out;
}

} // namespace roomprobe
