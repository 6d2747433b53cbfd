#pragma once
// CoarseRoomModel: the room as its floorplan extruded to the ceiling (§4.1), shown as a mesh
// with one texture atlas. The mesh is rebuilt, in the editor too, whenever the floorplan changes.

#include <room/room_mesh.h>

#include <rp_godot/godot.h>

namespace roomprobe {

class CoarseRoomModel : public godot::Node3D {
	GDCLASS(CoarseRoomModel, godot::Node3D)

public:
	CoarseRoomModel();

	void set_floorplan(const godot::PackedVector2Array &p_points);
	godot::PackedVector2Array get_floorplan() const;
	void set_ceiling_height(double p_metres);
	double get_ceiling_height() const;
	void set_texel_size(double p_metres);
	double get_texel_size() const;

	bool is_valid() const;
	godot::String get_floorplan_error() const;
	godot::Ref<godot::ArrayMesh> get_mesh() const;
	godot::Vector2i get_atlas_size() const;

	// What the node cannot do as configured; the editor shows these as configuration warnings.
	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }

protected:
	static void _bind_methods();
	void _notification(int p_what);

private:
	void rebuild();

	godot::PackedVector2Array floorplan;
	double ceiling_height = 2.5;
	double texel_size = 0.02;

	FloorplanCheck check;
	RoomMeshResult result;
	godot::Ref<godot::ArrayMesh> mesh;
	godot::MeshInstance3D *mesh_instance = nullptr;
};

} // namespace roomprobe
