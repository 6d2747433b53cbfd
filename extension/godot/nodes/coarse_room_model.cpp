#include "coarse_room_model.h"

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
	result = build_room_mesh(plan, options);
	mesh->clear_surfaces();
	if (result.ok) {
		mesh->add_surface_from_arrays(Mesh::PRIMITIVE_TRIANGLES, to_surface_arrays(result.mesh));
	}
	update_configuration_warnings();
	emit_signal("mesh_changed");
}

bool CoarseRoomModel::is_valid() const { return result.ok; }
String CoarseRoomModel::get_floorplan_error() const { return String(result.error.c_str()); }
Ref<ArrayMesh> CoarseRoomModel::get_mesh() const { return mesh; }

Vector2i CoarseRoomModel::get_atlas_size() const {
	return result.ok ? Vector2i(result.mesh.atlas_width, result.mesh.atlas_height) : Vector2i();
}

PackedStringArray CoarseRoomModel::get_warnings() const {
	PackedStringArray warnings;
	if (!result.ok) {
		// A valid floorplan can still fail to build (e.g. an atlas beyond the size limit).
		const char *phrase = check.ok ? "The room cannot be built" : floorplan_problem_summary(check.problem);
		warnings.push_back(String((std::string(phrase) + ": " + result.error).c_str()));
	}
	warnings.push_back("Texturing from the fisheye is not implemented yet (issue #4): the room shows its mesh only.");
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

	ADD_PROPERTY(PropertyInfo(Variant::PACKED_VECTOR2_ARRAY, "floorplan"), "set_floorplan", "get_floorplan");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "ceiling_height", PROPERTY_HINT_RANGE, "0.5,10,0.01,or_greater,suffix:m"), "set_ceiling_height", "get_ceiling_height");
	ADD_GROUP("Texture", "");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "texel_size", PROPERTY_HINT_RANGE, "0.005,0.1,0.001,suffix:m"), "set_texel_size", "get_texel_size");

	ADD_SIGNAL(MethodInfo("mesh_changed"));
}

} // namespace roomprobe
