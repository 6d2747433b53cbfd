#include "engine_config.h"

namespace roomprobe {

void config_from_rig(const Rig &p_rig, const RigPhotometry &p_photometry, const RoomInfo *p_room, bool p_take_room, LiveRoomConfig *io_config) {
	io_config->has_rig = true;
	io_config->rig = p_rig;
	io_config->photometry = p_photometry; // unknown for a rig file without photometry (version 1)
	io_config->initial_rgb_pose = p_room != nullptr ? p_room->initial_rgb_pose : upright_first_rgb_pose(p_rig.has_fisheye(), p_rig.rgb_from_fisheye);
	// Eviction spares the probes' surroundings longest.
	io_config->keep_points = p_room != nullptr ? p_room->probes : std::vector<glm::dvec3>();
	io_config->ground_truth.clear();
	if (p_take_room) {
		io_config->has_room = p_room != nullptr;
		if (p_room != nullptr) {
			io_config->floorplan = p_room->floorplan;
		}
	}
}

void config_from_recording(const RecordingReader &p_reader, const RigPhotometry &p_photometry, bool p_take_room, LiveRoomConfig *io_config) {
	config_from_rig(p_reader.get_rig(), p_photometry, p_reader.has_room() ? &p_reader.get_room() : nullptr, p_take_room, io_config);
	if (p_reader.has_ground_truth_trajectory(RecordingStream::Rgbd)) {
		io_config->ground_truth = p_reader.ground_truth_trajectory(RecordingStream::Rgbd);
	}
}

std::string config_from_recording(const RecordingReader &p_reader, bool p_take_room, LiveRoomConfig *io_config) {
	RigPhotometry photometry;
	std::string error;
	if (!read_recording_photometry(p_reader.get_folder(), p_reader.get_rig().photometry, &photometry, &error)) {
		return error;
	}
	config_from_recording(p_reader, photometry, p_take_room, io_config);
	return std::string();
}

} // namespace roomprobe
