#include "occlusion.h"

#include <io/embree_scene.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace roomprobe {

bool floorplan_is_convex(const Floorplan &p_floorplan) {
	using K = CGAL::Exact_predicates_inexact_constructions_kernel;
	const size_t n = p_floorplan.points.size();
	if (n < 3) {
		return false;
	}
	const Floorplan plan = normalized(p_floorplan);
	for (size_t i = 0; i < n; ++i) {
		const Vec2 &a = plan.points[i], &b = plan.points[(i + 1) % n], &c = plan.points[(i + 2) % n];
		if (CGAL::orientation(K::Point_2(a.x, a.y), K::Point_2(b.x, b.y), K::Point_2(c.x, c.y)) == CGAL::RIGHT_TURN) {
			return false;
		}
	}
	return true;
}

bool point_in_polygon(const std::vector<glm::dvec2> &p_polygon, const glm::dvec2 &p_point) {
	bool inside = false;
	const size_t n = p_polygon.size();
	for (size_t i = 0, j = n - 1; i < n; j = i++) {
		const glm::dvec2 &a = p_polygon[i], &b = p_polygon[j];
		if ((a.y > p_point.y) != (b.y > p_point.y)) {
			const double x = a.x + (p_point.y - a.y) / (b.y - a.y) * (b.x - a.x);
			if (p_point.x < x) {
				inside = !inside;
			}
		}
	}
	return inside;
}

namespace {

// 255 at the surface texels inside the visibility polygon (walls tested wall_inset_m inside), in
// the tiles p_projection sees (all when it is null); r_mask (atlas-sized) is left as it is elsewhere.
void mask_texels(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const VisibilityPolygon &p_polygon, const TexelProjection *p_projection,
		const OcclusionOptions &p_options, cv::Mat *r_mask) {
	const int w = p_geometry.width, h = p_geometry.height, size = TexelGeometry::tile_size;
	const double inset = p_options.wall_inset_m;
	tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int> &p_rows) {
		for (int y = p_rows.begin(); y < p_rows.end(); ++y) {
			uint8_t *row = r_mask->ptr<uint8_t>(y);
			for (int x = 0; x < w; ++x) {
				if (p_projection && x % size == 0 && !p_projection->seen(p_geometry, x, y)) {
					x += size - 1; // the fisheye does not see the tile: the update skips it
					continue;
				}
				const size_t i = size_t(y) * w + x;
				const int chart = p_geometry.charts[i];
				if (chart < 0) {
					continue;
				}
				glm::dvec3 point = p_geometry.points[i];
				if (p_mesh.charts[chart].kind == SurfaceKind::Wall) {
					point += inset * p_geometry.normals[i];
				}
				row[x] = point_in_polygon(p_polygon.points, glm::dvec2(point.x, point.z)) ? 255 : 0;
			}
		}
	});
}

} // namespace

cv::Mat occlusion_mask(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const glm::dvec3 &p_fisheye_position,
		const OcclusionOptions &p_options, VisibilityPolygon *r_polygon) {
	const int w = p_geometry.width, h = p_geometry.height;
	cv::Mat mask(h, w, CV_8UC1, cv::Scalar(0));
	if (p_options.skip_convex && floorplan_is_convex(p_mesh.floorplan)) {
		if (r_polygon) {
			*r_polygon = VisibilityPolygon();
			r_polygon->ok = true;
		}
		for (int y = 0; y < h; ++y) {
			uint8_t *row = mask.ptr<uint8_t>(y);
			for (int x = 0; x < w; ++x) {
				row[x] = p_geometry.charts[size_t(y) * w + x] >= 0 ? 255 : 0;
			}
		}
		return mask;
	}
	const VisibilityPolygon polygon = visibility_polygon(p_mesh.floorplan, glm::dvec2(p_fisheye_position.x, p_fisheye_position.z));
	if (r_polygon) {
		*r_polygon = polygon;
	}
	if (!polygon.ok) {
		return mask;
	}
	mask_texels(p_mesh, p_geometry, polygon, nullptr, p_options, &mask);
	return mask;
}

void occlusion_mask(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const glm::dvec3 &p_fisheye_position, const TexelProjection &p_projection,
		cv::Mat *r_mask, const OcclusionOptions &p_options) {
	r_mask->create(p_geometry.height, p_geometry.width, CV_8UC1);
	r_mask->setTo(cv::Scalar(0));
	const VisibilityPolygon polygon = visibility_polygon(p_mesh.floorplan, glm::dvec2(p_fisheye_position.x, p_fisheye_position.z));
	if (polygon.ok && p_projection.tile_seen.size() == size_t(p_geometry.tiles_x) * p_geometry.tiles_y) {
		mask_texels(p_mesh, p_geometry, polygon, &p_projection, p_options, r_mask);
	}
}

// ---------------------------------------------------------------- Embree

struct EmbreeOcclusion::Embree : EmbreeTriangleScene {};

EmbreeOcclusion::EmbreeOcclusion(const RoomMesh &p_mesh, const std::vector<glm::dvec3> &p_extra_triangles) :
		embree(std::make_unique<Embree>()) {
	std::vector<float> vertices;
	std::vector<uint32_t> indices;
	for (const Vec3f &p : p_mesh.positions) {
		vertices.insert(vertices.end(), { p.x, p.y, p.z });
	}
	indices = p_mesh.indices;
	for (size_t i = 0; i + 2 < p_extra_triangles.size(); i += 3) {
		for (int k = 0; k < 3; ++k) {
			const glm::dvec3 &p = p_extra_triangles[i + k];
			indices.push_back(static_cast<uint32_t>(vertices.size() / 3));
			vertices.insert(vertices.end(), { float(p.x), float(p.y), float(p.z) });
		}
	}
	if (indices.empty()) {
		error_message = "no triangles";
		return;
	}
	error_message = embree->build(vertices, indices, false);
}

EmbreeOcclusion::~EmbreeOcclusion() = default;

cv::Mat EmbreeOcclusion::mask(const TexelGeometry &p_geometry, const glm::dvec3 &p_fisheye_position, double p_epsilon_m) const {
	const int w = p_geometry.width, h = p_geometry.height;
	cv::Mat mask(h, w, CV_8UC1, cv::Scalar(0));
	if (!ok()) {
		return mask;
	}
	tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int> &p_rows) {
		for (int y = p_rows.begin(); y < p_rows.end(); ++y) {
			uint8_t *row = mask.ptr<uint8_t>(y);
			for (int x = 0; x < w; ++x) {
				const size_t i = size_t(y) * w + x;
				if (p_geometry.charts[i] < 0) {
					continue;
				}
				const glm::dvec3 direction = p_geometry.points[i] - p_fisheye_position;
				const double distance = glm::length(direction);
				if (!(distance > p_epsilon_m)) {
					row[x] = 255;
					continue;
				}
				row[x] = embree->occluded(p_fisheye_position, direction / distance, 0.0, distance - p_epsilon_m) ? 0 : 255;
			}
		}
	});
	return mask;
}

cv::Mat occlusion_mask_embree(const RoomMesh &p_mesh, const TexelGeometry &p_geometry, const glm::dvec3 &p_fisheye_position,
		const std::vector<glm::dvec3> &p_extra_triangles, double p_epsilon_m) {
	const EmbreeOcclusion tracer(p_mesh, p_extra_triangles);
	if (!tracer.ok()) {
		return cv::Mat();
	}
	return tracer.mask(p_geometry, p_fisheye_position, p_epsilon_m);
}

} // namespace roomprobe
