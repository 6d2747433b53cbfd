#pragma once
// DenseSLAM: tracks the RGB-D camera and keeps the dense colour model of nearby surfaces (§4.2).
// A thin shim over the live engine (engine/live_room.h) of its RigCapture: it turns dense SLAM on
// there with its volume settings, and each frame copies the engine's newest results into Godot:
// the AR Camera3D's transform together with the RGB image of that very frame (the background, so
// the two never slip apart), the tracking state, and the dense mesh. Placement rays are Embree's,
// in the engine.

#include "live_room_link.h"

#include <rp_godot/godot.h>

#include <map>
#include <memory>
#include <string>

namespace roomprobe {

class DenseSLAM : public godot::Node3D, public LiveRoomHost {
	GDCLASS(DenseSLAM, godot::Node3D)

public:
	enum TrackingState {
		TRACKING_NOT_STARTED, // No frame has been tracked.
		TRACKING_GOOD,
		TRACKING_POOR,
		TRACKING_LOST,
	};

	DenseSLAM();
	~DenseSLAM();

	void set_capture_path(const godot::NodePath &p_path);
	godot::NodePath get_capture_path() const;
	void set_camera_path(const godot::NodePath &p_path);
	godot::NodePath get_camera_path() const;
	godot::Node3D *driven_camera() const;
	void set_coarse_model_path(const godot::NodePath &p_path);
	godot::NodePath get_coarse_model_path() const;
	void set_voxel_size(double p_metres);
	double get_voxel_size() const;
	void set_truncation_distance(double p_metres);
	double get_truncation_distance() const;
	void set_max_blocks(int64_t p_blocks);
	int get_max_blocks() const;
	void set_colour_weight(double p_metres_per_intensity);
	double get_colour_weight() const;
	void set_tracking_max_depth(double p_metres);
	double get_tracking_max_depth() const;
	void set_fusion_max_depth(double p_metres);
	double get_fusion_max_depth() const;
	void set_mesh_layers(int64_t p_layers);
	uint32_t get_mesh_layers() const;
	void set_mesh_upload_budget(int64_t p_triangles);
	int get_mesh_upload_budget() const;
	void set_mesh_update_interval(int64_t p_frames);
	int get_mesh_update_interval() const;

	// Takes the engine's newest tracked RGB-D frame if it has not been taken yet (drives the
	// camera, signals); true when it did. Called every frame while the node processes.
	bool process_rig_frame();
	// The RGB image of the frame whose pose the camera has now: the AR view's background.
	godot::Ref<godot::ImageTexture> get_camera_image_texture() const;
	// Draws that image behind everything in 3D (an internal full-screen quad at the far plane):
	// an AR background with no script and no Environment change.
	void set_camera_background(bool p_enabled);
	bool get_camera_background() const;
	TrackingState get_tracking_state() const;
	godot::String get_tracking_reason() const;
	godot::Transform3D get_camera_transform() const;
	int64_t get_processed_frame_count() const;
	godot::Dictionary get_stats() const;
	godot::Ref<godot::ArrayMesh> get_mesh() const;
	void update_mesh();
	void reset();
	godot::Dictionary place_on_ray(const godot::Vector3 &p_origin, const godot::Vector3 &p_direction) const;
	godot::Dictionary place_on_surface(const godot::Vector2 &p_screen_position) const;

	std::shared_ptr<LiveRoom> get_live_room() const override { return engine; }

	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }

protected:
	static void _bind_methods();
	void _notification(int p_what);

public:
	void _process(double p_delta);

private:
	// Finds the RigCapture (by path, or the one in the scene) and turns dense SLAM on in its engine.
	void connect_engine();
	void disconnect_engine();
	void push_settings();
	void take_mesh();
	bool settings_valid() const;
	void set_state(TrackingState p_state, const std::string &p_reason);

	godot::NodePath capture_path;
	godot::NodePath camera_path;
	godot::NodePath coarse_model_path;
	double voxel_size = 0.01;
	double truncation_distance = 0.04;
	int max_blocks = 40000;
	double colour_weight = 0.3;
	double tracking_max_depth = 8.0;
	double fusion_max_depth = 4.0;
	uint32_t mesh_layers = 1u << 19; // layer 20, with the room
	int mesh_update_interval = 15;

	std::shared_ptr<LiveRoom> engine;
	uint64_t taken_sequence = 0; // of the last TrackedFrame copied
	uint64_t taken_mesh = 0; // version of the last dense mesh whose signal was sent
	std::shared_ptr<const DenseMeshSnapshot> shown_mesh; // the newest snapshot taken
	mutable uint64_t whole_mesh_version = 0; // of the snapshot get_mesh() last converted
	struct ChunkView {
		uint64_t version = 0;
		godot::MeshInstance3D *instance = nullptr;
	};
	std::map<glm::ivec3, ChunkView, IvecLess> chunk_views; // the displayed regions
	int mesh_upload_budget = 4000;
	std::shared_ptr<const TrackedFrame> last_frame;
	int64_t processed = 0;
	TrackingState tracking_state = TRACKING_NOT_STARTED;
	std::string tracking_reason;

	mutable godot::Ref<godot::ArrayMesh> mesh; // the whole mesh, made when get_mesh() asks
	godot::Node3D *mesh_root = nullptr; // holds one MeshInstance3D per region
	void show_chunks();
	godot::Ref<godot::StandardMaterial3D> material;
	mutable godot::Ref<godot::ImageTexture> camera_image;
	mutable bool camera_image_wanted = false;
	bool camera_background = true;
	uint64_t masked_camera = 0; // the AR camera whose cull mask was last cleared of the room's layers
	uint32_t masked_camera_mask = 0; // and the mask it was left with
	godot::MeshInstance3D *background = nullptr; // internal, while camera_background is on
	void update_background();
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::DenseSLAM::TrackingState)
