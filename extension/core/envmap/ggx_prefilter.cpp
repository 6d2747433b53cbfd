#include "ggx_prefilter.h"

#include <types/cubemap_layout.h>

#include <glm/geometric.hpp>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <future>
#include <map>
#include <mutex>
#include <numbers>
#include <utility>

namespace roomprobe {

namespace {

constexpr double PI = std::numbers::pi;

// GGX's normal distribution, alpha = roughness^2.
double ggx_d(double p_cos_h, double p_alpha) {
	const double a2 = p_alpha * p_alpha;
	const double d = p_cos_h * p_cos_h * (a2 - 1.0) + 1.0;
	return a2 / (PI * d * d);
}

double radical_inverse(uint32_t p_bits) {
	p_bits = (p_bits << 16u) | (p_bits >> 16u);
	p_bits = ((p_bits & 0x55555555u) << 1u) | ((p_bits & 0xAAAAAAAAu) >> 1u);
	p_bits = ((p_bits & 0x33333333u) << 2u) | ((p_bits & 0xCCCCCCCCu) >> 2u);
	p_bits = ((p_bits & 0x0F0F0F0Fu) << 4u) | ((p_bits & 0xF0F0F0F0u) >> 4u);
	p_bits = ((p_bits & 0x00FF00FFu) << 8u) | ((p_bits & 0xFF00FF00u) >> 8u);
	return double(p_bits) * 2.3283064365386963e-10;
}

using Tap = std::pair<uint32_t, double>; // flattened pyramid texel, weight

// The bilinear taps of p_direction on a face of p_size texels whose first texel is p_offset in the
// flattened pyramid, clamped at the face's edges, scaled by p_scale.
void bilinear_taps(const glm::dvec3 &p_direction, int p_size, size_t p_offset, double p_scale, std::vector<Tap> *r_taps) {
	const CubemapBilinear read = cubemap_bilinear(p_direction, p_size);
	const size_t n = size_t(p_size);
	for (size_t k = 0; k < 4; k++) {
		r_taps->emplace_back(uint32_t(p_offset + (size_t(read.face) * n + size_t(read.y[k])) * n + size_t(read.x[k])), p_scale * read.weight[k]);
	}
}

// One output texel's taps: GGX samples around p_r, each read at the box level of its share of
// the lobe (filtered importance sampling), blended between the two nearest levels, and never
// finer than p_finest_level: an output texel of level k spans 2^k source texels already, so
// reading much finer adds taps (memory, time) and no detail.
std::vector<Tap> texel_taps(const glm::dvec3 &p_r, double p_alpha, int p_samples, double p_finest_level, const std::vector<int> &p_sizes,
		const std::vector<size_t> &p_offsets) {
	std::vector<Tap> taps;
	taps.reserve(size_t(p_samples) * 8);
	// The source texel's solid angle at level 0 (about; the cube's texels vary by 5x).
	const double texel_solid_angle = 4.0 * PI / (6.0 * double(p_sizes[0]) * double(p_sizes[0]));
	const double top = double(p_sizes.size() - 1);
	// A frame around R.
	const glm::dvec3 helper = std::abs(p_r.z) < 0.999 ? glm::dvec3(0.0, 0.0, 1.0) : glm::dvec3(1.0, 0.0, 0.0);
	const glm::dvec3 t = glm::normalize(glm::cross(helper, p_r));
	const glm::dvec3 b = glm::cross(p_r, t);
	for (int s = 0; s < p_samples; s++) {
		const double u1 = (s + 0.5) / p_samples, u2 = radical_inverse(uint32_t(s));
		// h from D(h) (n . h): cos^2 = (1 - u) / (1 + (a^2 - 1) u).
		const double cos_h = std::sqrt((1.0 - u1) / (1.0 + (p_alpha * p_alpha - 1.0) * u1));
		const double sin_h = std::sqrt(std::max(0.0, 1.0 - cos_h * cos_h));
		const double phi = 2.0 * PI * u2;
		const glm::dvec3 h = sin_h * std::cos(phi) * t + sin_h * std::sin(phi) * b + cos_h * p_r;
		const glm::dvec3 l = 2.0 * glm::dot(p_r, h) * h - p_r;
		const double r_dot_l = glm::dot(p_r, l);
		if (r_dot_l <= 0.0) {
			continue;
		}
		// pdf of l: D(h) (n . h) / (4 (l . h)) = D(h) / 4 with n = v = R.
		const double pdf = ggx_d(cos_h, p_alpha) / 4.0;
		const double sample_solid_angle = 1.0 / (double(p_samples) * pdf);
		const double lod = std::clamp(0.5 * std::log2(sample_solid_angle / texel_solid_angle) + 1.0, p_finest_level, top);
		const int l0 = int(lod);
		const int l1 = std::min(l0 + 1, int(top));
		const double f = lod - l0;
		bilinear_taps(l, p_sizes[size_t(l0)], p_offsets[size_t(l0)], r_dot_l * (1.0 - f), &taps);
		if (f > 0.0) {
			bilinear_taps(l, p_sizes[size_t(l1)], p_offsets[size_t(l1)], r_dot_l * f, &taps);
		}
	}
	if (taps.empty()) { // no sample above the horizon: the source along R
		const size_t level = size_t(p_finest_level);
		bilinear_taps(p_r, p_sizes[level], p_offsets[level], 1.0, &taps);
	}
	// Merge repeated texels and normalise.
	std::sort(taps.begin(), taps.end(), [](const Tap &p_a, const Tap &p_b) { return p_a.first < p_b.first; });
	std::vector<Tap> merged;
	double total = 0.0;
	for (const Tap &tap : taps) {
		if (tap.second <= 0.0) {
			continue;
		}
		total += tap.second;
		if (!merged.empty() && merged.back().first == tap.first) {
			merged.back().second += tap.second;
		} else {
			merged.push_back(tap);
		}
	}
	// The smallest taps that together hold under TAIL of the weight are dropped: they are most
	// of the memory (the lobe's tail spread thin over many texels). A bound on the weight lost,
	// whatever the sample count.
	constexpr double TAIL = 0.005;
	std::vector<Tap> by_weight = merged;
	std::sort(by_weight.begin(), by_weight.end(), [](const Tap &p_a, const Tap &p_b) { return p_a.second < p_b.second; });
	double dropped = 0.0, threshold = 0.0;
	for (const Tap &tap : by_weight) {
		if (dropped + tap.second > TAIL * total) {
			break;
		}
		dropped += tap.second;
		threshold = tap.second;
	}
	if (dropped > 0.0) {
		std::erase_if(merged, [&](const Tap &p_tap) { return p_tap.second <= threshold; });
	}
	double kept = 0.0;
	for (const Tap &tap : merged) {
		kept += tap.second;
	}
	for (Tap &tap : merged) {
		tap.second /= kept;
	}
	return merged;
}

// Per output texel (p_first: its taps' range in p_texel), a bit per source face its taps read:
// a pyramid texel's face follows from its box level's offset and size.
std::vector<uint8_t> source_face_bits(const std::vector<uint32_t> &p_first, const std::vector<uint32_t> &p_texel, const std::vector<size_t> &p_offset,
		const std::vector<int> &p_sizes) {
	std::vector<uint8_t> bits(p_first.empty() ? 0 : p_first.size() - 1, 0);
	for (size_t t = 0; t < bits.size(); t++) {
		for (uint32_t i = p_first[t]; i < p_first[t + 1]; i++) {
			const size_t l = size_t(std::upper_bound(p_offset.begin(), p_offset.end(), size_t(p_texel[i])) - p_offset.begin()) - 1;
			const size_t n = size_t(p_sizes[l]);
			bits[t] |= uint8_t(1u << ((size_t(p_texel[i]) - p_offset[l]) / (n * n)));
		}
	}
	return bits;
}

} // namespace

double ggx_level_roughness(int p_level, int p_levels) {
	if (p_levels <= 1) {
		return 0.0;
	}
	const double t = double(p_level) / double(p_levels - 1);
	return t * t;
}

int ggx_default_levels(int p_size) {
	int levels = 0;
	for (int n = p_size; n >= 4; n /= 2) {
		levels++;
	}
	return std::max(1, levels);
}

GgxFilter::GgxFilter(int p_size, const GgxPrefilterOptions &p_options) {
	const int level_count = p_options.levels == 0 ? ggx_default_levels(p_size) : p_options.levels;
	if (p_size < 1 || level_count < 1 || p_options.samples < 1 || (p_size >> (level_count - 1)) < 1) {
		return;
	}
	std::vector<int> sizes;
	size_t texels = 0;
	for (int n = p_size;; n = std::max(1, n / 2)) {
		sizes.push_back(n);
		pyramid_offset.push_back(texels);
		texels += size_t(6) * size_t(n) * size_t(n);
		if (n == 1) {
			break;
		}
	}
	if (texels > size_t(UINT32_MAX)) {
		pyramid_offset.clear();
		return;
	}
	size = p_size;
	samples = p_options.samples;
	for (int k = 1; k < level_count; k++) {
		const double roughness = ggx_level_roughness(k, level_count);
		const double alpha = std::max(roughness * roughness, 1e-6);
		Level level;
		level.size = p_size >> k;
		const int n = level.size;
		std::vector<std::vector<Tap>> per_texel(size_t(6) * size_t(n) * size_t(n));
		tbb::parallel_for(0, 6 * n, [&](int p_row) {
			const int face = p_row / n, y = p_row % n;
			for (int x = 0; x < n; x++) {
				per_texel[size_t(p_row) * size_t(n) + size_t(x)] = texel_taps(cubemap_direction(face, x, y, n), alpha, samples, double(k - 1), sizes, pyramid_offset);
			}
		});
		level.first.reserve(per_texel.size() + 1);
		for (const std::vector<Tap> &taps : per_texel) {
			level.first.push_back(uint32_t(level.texel.size()));
			for (const Tap &tap : taps) {
				level.texel.push_back(tap.first);
				level.weight.push_back(float(tap.second));
			}
		}
		level.first.push_back(uint32_t(level.texel.size()));
		level.source_faces = source_face_bits(level.first, level.texel, pyramid_offset, sizes);
		levels.push_back(std::move(level));
	}
}

size_t GgxFilter::tap_count() const {
	size_t n = 0;
	for (const Level &level : levels) {
		n += level.weight.size();
	}
	return n;
}

size_t GgxFilter::memory_bytes() const {
	size_t bytes = 0;
	for (const Level &level : levels) {
		bytes += level.first.size() * sizeof(uint32_t) + level.texel.size() * sizeof(uint32_t) + level.weight.size() * sizeof(float);
	}
	return bytes;
}

std::vector<cv::Vec3f> GgxFilter::box_pyramid(const Cubemap &p_source) const {
	std::vector<cv::Vec3f> pyramid(pyramid_texels());
	Cubemap level = p_source;
	for (size_t l = 0; l < pyramid_offset.size(); l++) {
		const int n = level.size;
		for (int f = 0; f < 6; f++) {
			const cv::Mat &face = level.faces[size_t(f)];
			for (int y = 0; y < n; y++) {
				std::copy_n(face.ptr<cv::Vec3f>(y), n, pyramid.begin() + std::ptrdiff_t(pyramid_offset[l] + (size_t(f) * size_t(n) + size_t(y)) * size_t(n)));
			}
		}
		if (n > 1) {
			Cubemap next;
			next.size = n / 2;
			for (int f = 0; f < 6; f++) {
				cv::resize(level.faces[size_t(f)], next.faces[size_t(f)], cv::Size(next.size, next.size), 0.0, 0.0, cv::INTER_AREA);
			}
			level = std::move(next);
		}
	}
	return pyramid;
}

std::vector<Cubemap> GgxFilter::apply(const Cubemap &p_source) const {
	return apply(p_source, {}, 0x3F, nullptr);
}

std::vector<Cubemap> GgxFilter::apply(const Cubemap &p_source, const std::vector<Cubemap> &p_previous, uint8_t p_changed_faces, uint8_t *r_changed_faces) const {
	std::vector<Cubemap> chain;
	if (r_changed_faces != nullptr) {
		*r_changed_faces = 0;
	}
	if (!is_valid() || !is_valid_cubemap(p_source) || p_source.size != size) {
		return chain;
	}
	bool reuse = p_previous.size() == levels.size() + 1;
	for (size_t l = 0; reuse && l < levels.size(); l++) {
		reuse = p_previous[l + 1].size == levels[l].size;
	}
	const uint8_t changed = reuse ? uint8_t(p_changed_faces & 0x3F) : uint8_t(0x3F);
	const std::vector<cv::Vec3f> pyramid = box_pyramid(p_source);
	chain.push_back(p_source); // level 0: the source itself, its pixels shared (no copy)
	std::atomic<uint8_t> computed{ changed };
	for (size_t l = 0; l < levels.size(); l++) {
		const Level &filter = levels[l];
		Cubemap out = make_cubemap(filter.size);
		const int n = filter.size;
		tbb::parallel_for(0, 6 * n, [&](int p_row) {
			const int face = p_row / n, y = p_row % n;
			cv::Vec3f *row = out.faces[size_t(face)].ptr<cv::Vec3f>(y);
			const cv::Vec3f *old_row = reuse ? p_previous[l + 1].faces[size_t(face)].ptr<cv::Vec3f>(y) : nullptr;
			bool any = false;
			for (int x = 0; x < n; x++) {
				const size_t texel = size_t(p_row) * size_t(n) + size_t(x);
				if ((filter.source_faces[texel] & changed) == 0) {
					row[x] = old_row[x]; // reads no changed face (changed is all faces without a previous chain)
					continue;
				}
				any = true;
				cv::Vec3f sum(0.0f, 0.0f, 0.0f);
				for (uint32_t i = filter.first[texel]; i < filter.first[texel + 1]; i++) {
					sum += pyramid[filter.texel[i]] * filter.weight[i];
				}
				row[x] = sum;
			}
			if (any) {
				computed.fetch_or(uint8_t(1u << face), std::memory_order_relaxed);
			}
		});
		chain.push_back(std::move(out));
	}
	if (r_changed_faces != nullptr) {
		*r_changed_faces = computed.load();
	}
	return chain;
}

std::shared_ptr<const GgxFilter> shared_ggx_filter(int p_size, bool p_wait) {
	using Build = std::shared_future<std::shared_ptr<const GgxFilter>>;
	static std::mutex mutex;
	static std::map<int, Build> builds;
	constexpr int AT_ONCE_SIZE = 64;
	if (p_size < 1) {
		return nullptr;
	}
	Build build;
	{
		const std::lock_guard<std::mutex> lock(mutex);
		auto it = builds.find(p_size);
		if (it == builds.end()) {
			const auto make = [p_size] { return std::shared_ptr<const GgxFilter>(std::make_shared<const GgxFilter>(p_size)); };
			it = builds.emplace(p_size, std::async(p_size <= AT_ONCE_SIZE ? std::launch::deferred : std::launch::async, make).share()).first;
		}
		build = it->second;
	}
	if (p_wait || build.wait_for(std::chrono::seconds(0)) != std::future_status::timeout) {
		return build.get(); // a deferred build runs here, once
	}
	return nullptr;
}

std::vector<Cubemap> prefilter_ggx(const Cubemap &p_source, const GgxPrefilterOptions &p_options) {
	if (!is_valid_cubemap(p_source)) {
		return {};
	}
	return GgxFilter(p_source.size, p_options).apply(p_source);
}

Cubemap ggx_reference(const Cubemap &p_source, double p_roughness, int p_size) {
	Cubemap out = make_cubemap(p_size);
	if (!is_valid_cubemap(p_source) || p_size < 1) {
		return out;
	}
	const double alpha = std::max(p_roughness * p_roughness, 1e-4);
	const int n = p_source.size;
	std::vector<glm::dvec3> directions, values;
	std::vector<double> solid_angles;
	for (int f = 0; f < 6; f++) {
		for (int y = 0; y < n; y++) {
			for (int x = 0; x < n; x++) {
				directions.push_back(cubemap_direction(f, x, y, n));
				const cv::Vec3f &c = p_source.faces[size_t(f)].at<cv::Vec3f>(y, x);
				values.emplace_back(c[0], c[1], c[2]);
				solid_angles.push_back(cubemap_texel_solid_angle(x, y, n));
			}
		}
	}
	tbb::parallel_for(0, 6 * p_size, [&](int p_row) {
		const int face = p_row / p_size, y = p_row % p_size;
		cv::Vec3f *row = out.faces[size_t(face)].ptr<cv::Vec3f>(y);
		for (int x = 0; x < p_size; x++) {
			const glm::dvec3 r = cubemap_direction(face, x, y, p_size);
			glm::dvec3 sum(0.0);
			double weight = 0.0;
			for (size_t i = 0; i < directions.size(); i++) {
				const double r_dot_l = glm::dot(r, directions[i]);
				if (r_dot_l <= 0.0) {
					continue;
				}
				const glm::dvec3 h = glm::normalize(r + directions[i]);
				const double w = ggx_d(glm::dot(r, h), alpha) * r_dot_l * solid_angles[i];
				sum += values[i] * w;
				weight += w;
			}
			const glm::dvec3 c = weight > 0.0 ? sum / weight : glm::dvec3(0.0);
			row[x] = cv::Vec3f(float(c.x), float(c.y), float(c.z));
		}
	});
	return out;
}

} // namespace roomprobe
