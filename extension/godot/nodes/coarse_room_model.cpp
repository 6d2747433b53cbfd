#include "coarse_room_model.h"

#include "../convert/image_convert.h"

#include <atomic>
#include <cstring>

using namespace godot;

namespace roomprobe {

namespace {

// The mesh's arrays in Godot's layout. Godot's front faces are clockwise, the core's are
// counter-clockwise as seen from inside the room: each triangle is reversed here.
Array to_surface_arrays(const RoomMesh &p_mesh) {
	PackedVector3Array vertices, normals;
	PackedVector2Array uvs;
	PackedInt32Array indices;
	vertices.resize(int64_t(p_mesh.positions.size()));
	normals.resize(int64_t(p_mesh.normals.size()));
	uvs.resize(int64_t(p_mesh.uvs.size()));
	for (size_t i = 0; i < p_mesh.positions.size(); i++) {
		const Vec3f &p = p_mesh.positions[i];
		const Vec3f &n = p_mesh.normals[i];
		vertices[int64_t(i)] = Vector3(p.x, p.y, p.z);
		normals[int64_t(i)] = Vector3(n.x, n.y, n.z);
		uvs[int64_t(i)] = Vector2(p_mesh.uvs[i].x, p_mesh.uvs[i].y);
	}
	indices.resize(int64_t(p_mesh.indices.size()));
	for (size_t t = 0; t + 2 < p_mesh.indices.size(); t += 3) {
		indices[int64_t(t)] = int32_t(p_mesh.indices[t]);
		indices[int64_t(t + 1)] = int32_t(p_mesh.indices[t + 2]);
		indices[int64_t(t + 2)] = int32_t(p_mesh.indices[t + 1]);
	}
	Array arrays;
	arrays.resize(Mesh::ARRAY_MAX);
	arrays[Mesh::ARRAY_VERTEX] = vertices;
	arrays[Mesh::ARRAY_NORMAL] = normals;
	arrays[Mesh::ARRAY_TEX_UV] = uvs;
	arrays[Mesh::ARRAY_INDEX] = indices;
	return arrays;
}

std::atomic<uint64_t> next_mesh_version{ 1 };

bool same(const Vec3 &p_a, const Vec3 &p_b) {
	return p_a.x == p_b.x && p_a.y == p_b.y && p_a.z == p_b.z;
}

} // namespace

CoarseRoomModel::CoarseRoomModel() {
	mesh.instantiate();
	// Built at once, so that a new node already reports why its (empty) floorplan is no room.
	rebuild();
}

void CoarseRoomModel::_notification(int p_what) {
	if (p_what == NOTIFICATION_READY && mesh_instance == nullptr) {
		// An internal child: it is not saved with the scene and the editor does not list it.
		mesh_instance = memnew(MeshInstance3D);
		mesh_instance->set_mesh(mesh);
		add_child(mesh_instance, false, Node::INTERNAL_MODE_FRONT);
		rebuild();
		apply_material();
	}
}

void CoarseRoomModel::set_floorplan(const PackedVector2Array &p_points) {
	floorplan = p_points;
	rebuild();
}

PackedVector2Array CoarseRoomModel::get_floorplan() const { return floorplan; }

void CoarseRoomModel::set_ceiling_height(double p_metres) {
	ceiling_height = p_metres;
	rebuild();
}

double CoarseRoomModel::get_ceiling_height() const { return ceiling_height; }

void CoarseRoomModel::set_texel_size(double p_metres) {
	texel_size = p_metres;
	rebuild();
}

double CoarseRoomModel::get_texel_size() const { return texel_size; }

void CoarseRoomModel::rebuild() {
	Floorplan plan;
	plan.ceiling_height_m = ceiling_height;
	for (int64_t i = 0; i < floorplan.size(); i++) {
		plan.points.push_back({ floorplan[i].x, floorplan[i].y });
	}
	RoomMeshOptions options;
	options.texel_size_m = texel_size;
	check = check_floorplan(plan);
	const std::vector<Chart> old_charts = result.ok ? result.mesh.charts : std::vector<Chart>();
	const int old_w = result.mesh.atlas_width;
	const int old_h = result.mesh.atlas_height;
	result = build_room_mesh(plan, options);
	mesh->clear_surfaces();
	if (result.ok) {
		mesh->add_surface_from_arrays(Mesh::PRIMITIVE_TRIANGLES, to_surface_arrays(result.mesh));
	}
	mesh_version = next_mesh_version.fetch_add(1);
	// The texture survives a rebuild that leaves the atlas layout as it was (entering the tree,
	// setting a value again); a new layout makes the old texture data meaningless.
	bool same_layout = result.ok && textured && old_w == result.mesh.atlas_width && old_h == result.mesh.atlas_height &&
			old_charts.size() == result.mesh.charts.size();
	for (size_t i = 0; same_layout && i < old_charts.size(); i++) {
		const Chart &a = old_charts[i];
		const Chart &b = result.mesh.charts[i];
		same_layout = a.kind == b.kind && a.x == b.x && a.y == b.y && a.w == b.w && a.h == b.h && same(a.origin_m, b.origin_m) &&
				same(a.u_axis_m, b.u_axis_m) && same(a.v_axis_m, b.v_axis_m);
	}
	if (!same_layout) {
		texture = result.ok ? make_coarse_texture(result.mesh) : CoarseTexture();
		textured = false;
	}
	apply_material();
	update_configuration_warnings();
	emit_signal("mesh_changed");
}

bool CoarseRoomModel::is_valid() const { return result.ok; }
String CoarseRoomModel::get_floorplan_error() const { return String(result.error.c_str()); }
Ref<ArrayMesh> CoarseRoomModel::get_mesh() const { return mesh; }

Vector2i CoarseRoomModel::get_atlas_size() const {
	return result.ok ? Vector2i(result.mesh.atlas_width, result.mesh.atlas_height) : Vector2i();
}

bool CoarseRoomModel::set_atlas_image(const Ref<Image> &p_image) {
	ERR_FAIL_COND_V_MSG(!result.ok, false, "The room has no valid mesh, so no atlas.");
	ERR_FAIL_COND_V_MSG(p_image.is_null(), false, "No image.");
	ERR_FAIL_COND_V_MSG(p_image->get_width() != result.mesh.atlas_width || p_image->get_height() != result.mesh.atlas_height, false,
			"The image must have the atlas's size (get_atlas_size()).");
	ERR_FAIL_COND_V_MSG(p_image->is_compressed(), false, "A compressed image cannot be used as the atlas.");
	// A copy: the caller's image is left as it is.
	Ref<Image> rgb = Image::create_from_data(p_image->get_width(), p_image->get_height(), p_image->has_mipmaps(), p_image->get_format(), p_image->get_data());
	ERR_FAIL_COND_V(rgb.is_null(), false);
	if (rgb->has_mipmaps()) {
		rgb->clear_mipmaps();
	}
	rgb->convert(Image::FORMAT_RGBF);
	const PackedByteArray data = rgb->get_data();
	const int w = result.mesh.atlas_width;
	const int h = result.mesh.atlas_height;
	ERR_FAIL_COND_V(data.size() != int64_t(w) * h * 3 * int64_t(sizeof(float)), false);
	std::memcpy(texture.color.data, data.ptr(), size_t(data.size()));
	for (int y = 0; y < h; y++) {
		uint8_t *observed = texture.observed.ptr<uint8_t>(y);
		float *quality = texture.quality.ptr<float>(y);
		for (int x = 0; x < w; x++) {
			const bool on = texel_to_world(result.mesh, x, y, nullptr, nullptr);
			observed[x] = on ? 255 : 0;
			quality[x] = on ? 1.0f : 0.0f;
		}
	}
	texture.updated = texture.observed.clone();
	textured = true;
	apply_material();
	return true;
}

Ref<Image> CoarseRoomModel::get_atlas_image() const {
	return textured ? image_from_mat(texture.color) : Ref<Image>();
}

bool CoarseRoomModel::has_texture_data() const { return textured; }

Array CoarseRoomModel::get_charts() const {
	Array charts;
	if (!result.ok) {
		return charts;
	}
	for (const Chart &c : result.mesh.charts) {
		Dictionary d;
		d.set("kind", String(c.kind == SurfaceKind::Wall ? "wall" : c.kind == SurfaceKind::Floor ? "floor" : "ceiling"));
		d.set("rect", Rect2i(c.x, c.y, c.w, c.h));
		d.set("normal", Vector3(real_t(c.normal.x), real_t(c.normal.y), real_t(c.normal.z)));
		d.set("wall_index", c.wall_index);
		charts.push_back(d);
	}
	return charts;
}

// Shows the atlas on the mesh (unshaded: the atlas already holds the room's light) while
// there is texture data; the plain mesh otherwise.
void CoarseRoomModel::apply_material() {
	if (mesh_instance == nullptr) {
		return;
	}
	if (!textured) {
		mesh_instance->set_material_override(Ref<Material>());
		return;
	}
	show_in_texture(image_from_mat(texture.color), atlas_texture);
	if (material.is_null()) {
		material.instantiate();
		material->set_shading_mode(BaseMaterial3D::SHADING_MODE_UNSHADED);
	}
	material->set_texture(BaseMaterial3D::TEXTURE_ALBEDO, atlas_texture);
	mesh_instance->set_material_override(material);
}

PackedStringArray CoarseRoomModel::get_warnings() const {
	PackedStringArray warnings;
	if (!result.ok) {
		// A valid floorplan can still fail to build (e.g. an atlas beyond the size limit).
		const char *phrase = check.ok ? "The room cannot be built" : floorplan_problem_summary(check.problem);
		warnings.push_back(String((std::string(phrase) + ": " + result.error).c_str()));
	}
	warnings.push_back("Texturing from the fisheye is not wired yet (issue #4): the atlas comes only from set_atlas_image().");
	return warnings;
}

void CoarseRoomModel::_bind_methods() {
	ClassDB::bind_method(D_METHOD("get_warnings"), &CoarseRoomModel::get_warnings);
	ClassDB::bind_method(D_METHOD("set_floorplan", "points"), &CoarseRoomModel::set_floorplan);
	ClassDB::bind_method(D_METHOD("get_floorplan"), &CoarseRoomModel::get_floorplan);
	ClassDB::bind_method(D_METHOD("set_ceiling_height", "metres"), &CoarseRoomModel::set_ceiling_height);
	ClassDB::bind_method(D_METHOD("get_ceiling_height"), &CoarseRoomModel::get_ceiling_height);
	ClassDB::bind_method(D_METHOD("set_texel_size", "metres"), &CoarseRoomModel::set_texel_size);
	ClassDB::bind_method(D_METHOD("get_texel_size"), &CoarseRoomModel::get_texel_size);
	ClassDB::bind_method(D_METHOD("is_valid"), &CoarseRoomModel::is_valid);
	ClassDB::bind_method(D_METHOD("get_floorplan_error"), &CoarseRoomModel::get_floorplan_error);
	ClassDB::bind_method(D_METHOD("get_mesh"), &CoarseRoomModel::get_mesh);
	ClassDB::bind_method(D_METHOD("get_atlas_size"), &CoarseRoomModel::get_atlas_size);
	ClassDB::bind_method(D_METHOD("set_atlas_image", "image"), &CoarseRoomModel::set_atlas_image);
	ClassDB::bind_method(D_METHOD("get_atlas_image"), &CoarseRoomModel::get_atlas_image);
	ClassDB::bind_method(D_METHOD("has_texture_data"), &CoarseRoomModel::has_texture_data);
	ClassDB::bind_method(D_METHOD("get_charts"), &CoarseRoomModel::get_charts);

	ADD_PROPERTY(PropertyInfo(Variant::PACKED_VECTOR2_ARRAY, "floorplan"), "set_floorplan", "get_floorplan");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "ceiling_height", PROPERTY_HINT_RANGE, "0.5,10,0.01,or_greater,suffix:m"), "set_ceiling_height", "get_ceiling_height");
	ADD_GROUP("Texture", "");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "texel_size", PROPERTY_HINT_RANGE, "0.005,0.1,0.001,suffix:m"), "set_texel_size", "get_texel_size");

	ADD_SIGNAL(MethodInfo("mesh_changed"));
}

} // namespace roomprobe
