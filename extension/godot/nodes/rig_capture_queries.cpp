// What RigCapture reports: frames, textures and images, the recording's room and rig, warnings.
#include "rig_capture.h"

#include <camera/pinhole_camera.h>

#include "../convert/image_convert.h"
#include "../convert/pose_convert.h"
#include "../convert/project_paths.h"

#include <recording/room_file.h>

#include <filesystem>

using namespace godot;

namespace roomprobe {

int64_t RigCapture::get_frame_count(Stream p_stream) const {
	if (live_open) {
		const std::lock_guard<std::mutex> lock(mutex);
		return live_frames[p_stream == STREAM_RGBD ? 0 : 1];
	}
	const RecordingReader *reader = recording_reader();
	if (!reader) {
		return 0;
	}
	return int64_t(p_stream == STREAM_RGBD ? reader->rgbd_count() : reader->fisheye_count());
}

int64_t RigCapture::get_event_count() const { return int64_t(player.recording().events().size()); }

int64_t RigCapture::get_event_position() const { return int64_t(player.position()); }

double RigCapture::get_time() const { return player.clock_s(); }
int64_t RigCapture::get_frame_index(Stream p_stream) const { return frame_index[p_stream == STREAM_RGBD ? 0 : 1]; }

double RigCapture::get_frame_timestamp(Stream p_stream) const {
	if (get_frame_index(p_stream) < 0) {
		return -1.0;
	}
	return p_stream == STREAM_RGBD ? rgbd_frame.timestamp_s : fisheye_frame.timestamp_s;
}

int64_t RigCapture::get_dropped_frame_count() const { return int64_t(player.dropped()); }

// The textures are made on first request and from then on follow the frames.
Ref<ImageTexture> RigCapture::get_rgb_texture() const {
	if (!textures_wanted) {
		textures_wanted = true;
		update_textures(frame_index[STREAM_RGBD] >= 0, frame_index[STREAM_FISHEYE] >= 0);
	}
	return rgb_texture;
}

void RigCapture::update_textures(bool p_rgbd, bool p_fisheye) const {
	if (p_rgbd) {
		show_in_texture(image_from_mat(rgbd_frame.rgb), rgb_texture);
		show_in_texture(image_from_mat(rgbd_frame.depth_m), depth_texture);
	}
	if (p_fisheye) {
		show_in_texture(image_from_mat(fisheye_frame.image), fisheye_texture);
	}
}

Ref<ImageTexture> RigCapture::get_depth_texture() const {
	get_rgb_texture();
	return depth_texture;
}

Ref<ImageTexture> RigCapture::get_fisheye_texture() const {
	get_rgb_texture();
	return fisheye_texture;
}

Ref<Image> RigCapture::get_rgb_image() const {
	if (images_stale) {
		rgb_image = frame_index[STREAM_RGBD] >= 0 ? image_from_mat(rgbd_frame.rgb) : Ref<Image>();
		depth_image = frame_index[STREAM_RGBD] >= 0 ? image_from_mat(rgbd_frame.depth_m) : Ref<Image>();
		fisheye_image = frame_index[STREAM_FISHEYE] >= 0 ? image_from_mat(fisheye_frame.image) : Ref<Image>();
		images_stale = false;
	}
	return rgb_image;
}

Ref<Image> RigCapture::get_depth_image() const {
	get_rgb_image();
	return depth_image;
}

Ref<Image> RigCapture::get_fisheye_image() const {
	get_rgb_image();
	return fisheye_image;
}

PackedStringArray RigCapture::get_issues() const {
	PackedStringArray out;
	if (const RecordingReader *reader = recording_reader()) {
		for (const RecordingIssue &issue : reader->get_issues()) {
			out.push_back(String(roomprobe::to_string(issue).c_str()));
		}
	}
	return out;
}

String RigCapture::get_last_error() const { return String(last_error.c_str()); }

const RoomInfo *RigCapture::room_info() const {
	if (live_open) {
		return has_live_room ? &live_room : nullptr;
	}
	if (const RecordingReader *reader = recording_reader()) {
		return reader->has_room() ? &reader->get_room() : nullptr;
	}
	return preview_room();
}

// Before the recording is opened (in the editor nothing opens it), a CoarseRoomModel with
// floorplan_source Recording should still show its room: the folder's room.yaml alone is read
// (not a zip's: that would unpack it).
const RoomInfo *RigCapture::preview_room() const {
	if (source != SOURCE_RECORDING || recording_path.is_empty() ||
			recording_path.to_lower().ends_with(".zip")) {
		return nullptr;
	}
	if (previewed_path != recording_path) {
		previewed_path = recording_path;
		has_preview_room = false;
		std::string error;
		const std::string folder = disk_path_for(recording_path, &error);
		if (error.empty() && !folder.empty()) {
			const RoomLoadResult loaded = load_room_file((std::filesystem::path(folder) / "room.yaml").string());
			has_preview_room = loaded.ok;
			preview = loaded.room;
		}
	}
	return has_preview_room ? &preview : nullptr;
}

const Rig *RigCapture::rig_info() const {
	const RecordingReader *reader = recording_reader();
	return live_open ? &live_rig : reader ? &reader->get_rig() : nullptr;
}

const RecordingReader *RigCapture::recording_reader() const {
	return player.is_open() ? &player.recording().reader() : nullptr;
}

PackedVector2Array RigCapture::get_room_floorplan() const {
	PackedVector2Array points;
	if (const RoomInfo *room = room_info()) {
		for (const Vec2 &p : room->floorplan.points) {
			points.push_back(Vector2(real_t(p.x), real_t(p.y)));
		}
	}
	return points;
}

double RigCapture::get_room_ceiling_height() const {
	const RoomInfo *room = room_info();
	return room ? room->floorplan.ceiling_height_m : 0.0;
}

PackedVector3Array RigCapture::get_probe_positions() const {
	PackedVector3Array out;
	if (const RoomInfo *room = room_info()) {
		for (const glm::dvec3 &p : room->probes) {
			out.push_back(Vector3(real_t(p.x), real_t(p.y), real_t(p.z)));
		}
	}
	return out;
}

bool RigCapture::has_ground_truth() const {
	const RecordingReader *reader = recording_reader();
	return reader && reader->has_ground_truth_trajectory(RecordingStream::Rgbd);
}

Transform3D RigCapture::get_ground_truth_camera_transform() const {
	Pose pose;
	std::string error;
	if (!has_ground_truth() || frame_index[STREAM_RGBD] < 0 ||
			!recording_reader()->ground_truth_trajectory(RecordingStream::Rgbd).pose_at(rgbd_frame.timestamp_s, &pose, &error)) {
		return Transform3D();
	}
	return camera_transform_from_pose(pose);
}

double RigCapture::get_rgb_camera_fov() const {
	const Rig *rig = rig_info();
	if (!rig) {
		return 0.0;
	}
	return pinhole_vertical_fov_degrees(rig->rgb);
}

PackedStringArray RigCapture::get_warnings() const {
	PackedStringArray warnings;
	if (source == SOURCE_RECORDING && recording_path.is_empty()) {
		warnings.push_back("Set recording_path to a recording folder (docs/recording-format.md), or set source to Live.");
	}
	if (source == SOURCE_LIVE && rig_file.is_empty()) {
		warnings.push_back("Set rig_file to the rig's calibration file (calib/README.md): source Live needs it.");
	}
	if (!last_error.empty()) {
		warnings.push_back(String(((source == SOURCE_LIVE ? "The live rig cannot run: " : "The recording cannot be played: ") + last_error).c_str()));
	} else if (source == SOURCE_RECORDING && !recording_path.is_empty() && !player.is_open()) {
		// Not opened yet (the editor): whether it would open, read once per path (indexes only).
		const std::string key = recording_path.utf8_string();
		if (key != checked_recording) {
			checked_recording = key;
			const std::string folder = disk_path_for(recording_path, &recording_problem);
			if (recording_problem.empty()) {
				const RecordingStatus status = RecordingReader().open(folder);
				recording_problem = status.ok ? "" : status.error;
			}
		}
		if (!recording_problem.empty()) {
			warnings.push_back(String(("recording_path cannot be played: " + recording_problem).c_str()));
		}
	} else if (source == SOURCE_LIVE && !rig_file.is_empty() && !live_open) {
		const std::string key = rig_file.utf8_string();
		if (key != checked_rig) {
			checked_rig = key;
			const std::string file = disk_path_for(rig_file, &rig_problem);
			if (rig_problem.empty()) {
				const RigLoadResult loaded = load_rig(file);
				rig_problem = loaded.ok ? "" : loaded.error;
			}
		}
		if (!rig_problem.empty()) {
			warnings.push_back(String(("rig_file cannot be read: " + rig_problem).c_str()));
		}
	}
	if (source == SOURCE_LIVE && fisheye_backend == FISHEYE_BACKEND_CAMERA_FEED && (!auto_exposure || !fisheye_pixel_format.is_empty())) {
		// Godot's feeds take no exposure, gain or pixel format: say so rather than ignore them silently.
		warnings.push_back("fisheye_backend is Camera Feed: Godot's camera feeds take no exposure, gain or pixel format, so auto_exposure "
						   "off, exposure_us, gain and fisheye_pixel_format do not apply (the feed's own settings stay).");
	}
	if (compute_backend != COMPUTE_BACKEND_CPU && engine->is_configured()) {
		const LiveRoomStats stats = engine->stats();
		if (!stats.compute_on_device) {
			const char *what = stats.compute.rfind("CPU", 0) == 0 ? "the kernels run on the CPU: " : "some kernels went back to the CPU: ";
			warnings.push_back(String(("compute_backend: " + std::string(what) + stats.compute).c_str()));
		}
	}
	if (live_open && playing) {
		for (int s = 0; s < 2; s++) {
			const drivers::DeviceStatus &status = device_status[s];
			if (status.state == drivers::DeviceState::Stalled || status.state == drivers::DeviceState::Disconnected) {
				warnings.push_back(String(((s == STREAM_RGBD ? std::string("The RGB-D camera is ") : std::string("The fisheye is ")) +
						drivers::device_state_name(status.state) + ": " + status.reason).c_str()));
			}
		}
	}
	if (is_open() && !engine->config_pending() && !engine->configuration_error().empty()) {
		warnings.push_back(String(("The live engine is not running: " + engine->configuration_error()).c_str()));
	}
	return warnings;
}

} // namespace roomprobe
