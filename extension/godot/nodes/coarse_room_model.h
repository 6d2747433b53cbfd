#pragma once
// CoarseRoomModel: the room as its floorplan extruded to the ceiling (§4.1), shown as a mesh
// with one texture atlas. The mesh is rebuilt, in the editor too, whenever the floorplan changes.

#include <coarse/coarse_texture.h>
#include <room/room_mesh.h>

#include <cstdint>

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

	// The texture hook until the fisheye drives CoarseTexture (texture_update.h): puts a whole
	// atlas in (the atlas size, any uncompressed format; values taken as linear R, G, B, no sRGB
	// decoding) and marks every surface texel observed.
	bool set_atlas_image(const godot::Ref<godot::Image> &p_image);
	// The completed atlas as RGBF, or null while the model has no texture data.
	godot::Ref<godot::Image> get_atlas_image() const;
	bool has_texture_data() const;
	// One Dictionary per chart, in RoomMesh::charts order: kind ("wall", "floor", "ceiling"),
	// rect (Rect2i, atlas texels), normal (Vector3, into the room), wall_index (int, -1 if none).
	godot::Array get_charts() const;

	// For RoomProbe (C++ only). get_room_mesh is null while the floorplan is invalid.
	const RoomMesh *get_room_mesh() const { return result.ok ? &result.mesh : nullptr; }
	const CoarseTexture &get_texture() const { return texture; }
	// Changes (to a value never used before by any model) whenever the mesh is rebuilt.
	uint64_t get_mesh_version() const { return mesh_version; }

	// What the node cannot do as configured; the editor shows these as configuration warnings.
	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }

protected:
	static void _bind_methods();
	void _notification(int p_what);

private:
	void rebuild();
	void apply_material();

	godot::PackedVector2Array floorplan;
	double ceiling_height = 2.5;
	double texel_size = 0.02;

	FloorplanCheck check;
	RoomMeshResult result;
	godot::Ref<godot::ArrayMesh> mesh;
	godot::MeshInstance3D *mesh_instance = nullptr;

	uint64_t mesh_version = 0;
	CoarseTexture texture; // the atlas's size while the mesh is valid, empty otherwise
	bool textured = false; // whether texture holds data (set_atlas_image so far)
	godot::Ref<godot::ImageTexture> atlas_texture;
	godot::Ref<godot::StandardMaterial3D> material;
};

} // namespace roomprobe
