#pragma once
// DenseSLAM: tracks the RGB-D camera and keeps the dense colour model of nearby surfaces (§4.2).
// A thin shim over the core's DenseSlam (slam/dense_slam.h): it feeds RigCapture's RGB-D frames
// in, drives the AR Camera3D, shows the model's mesh and answers placement rays (Embree).

#include <placement/surface_placement.h>
#include <rig/rig.h>
#include <rig/trajectory.h>
#include <slam/dense_slam.h>

#include <rp_godot/godot.h>

#include <memory>
#include <string>

namespace roomprobe {

class RigCapture;

class DenseSLAM : public godot::Node3D {
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
	void set_coarse_model_path(const godot::NodePath &p_path);
	godot::NodePath get_coarse_model_path() const;
	void set_voxel_size(double p_metres);
	double get_voxel_size() const;
	void set_truncation_distance(double p_metres);
	double get_truncation_distance() const;
	void set_max_blocks(int p_blocks);
	int get_max_blocks() const;
	void set_mesh_layers(uint32_t p_layers);
	uint32_t get_mesh_layers() const;
	void set_mesh_update_interval(int p_frames);
	int get_mesh_update_interval() const;

	// Tracks and integrates capture's newest RGB-D frame if it has not been yet; true when it did.
	bool process_rig_frame();
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

	// For CoarseRoomModel and RoomProbe (C++ only).
	const DenseSlam *get_slam() const { return slam.get(); }
	// The fisheye's pose at its timestamp, from the tracked RGB-D trajectory (§4.3).
	bool fisheye_pose_at(double p_fisheye_timestamp_s, Pose *r_world_from_fisheye, std::string *r_error) const;

	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }

protected:
	static void _bind_methods();
	void _notification(int p_what);

public:
	void _process(double p_delta);

private:
	RigCapture *find_capture() const;
	bool ensure_slam(const RigCapture &p_rig);
	void set_state(TrackingState p_state, const std::string &p_reason);
	void refresh_placer_coarse() const;

	godot::NodePath capture_path;
	godot::NodePath camera_path;
	godot::NodePath coarse_model_path;
	double voxel_size = 0.01;
	double truncation_distance = 0.04;
	int max_blocks = 40000;
	uint32_t mesh_layers = 1;
	int mesh_update_interval = 15;

	std::unique_ptr<DenseSlam> slam;
	const void *slam_reader = nullptr; // the RecordingReader the model was started for
	Rig rig;
	Trajectory trajectory; // tracked RGB-D poses, RGB-D clock
	int64_t last_rgbd_index = -1;
	DenseSlamFrame last_frame;
	TrackingState tracking_state = TRACKING_NOT_STARTED;
	std::string tracking_reason;
	std::string problem; // why frames are not processed, for the warnings
	int frames_since_mesh = 0;

	godot::Ref<godot::ArrayMesh> mesh;
	godot::MeshInstance3D *mesh_instance = nullptr;
	godot::Ref<godot::StandardMaterial3D> material;
	mutable SurfacePlacer placer;
	mutable uint64_t placer_coarse_version = 0;
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::DenseSLAM::TrackingState)
