#include "rig_capture.h"

using namespace godot;

namespace roomprobe {

void RigCapture::set_recording_path(const String &p_path) {
	recording_path = p_path;
	update_configuration_warnings();
}

String RigCapture::get_recording_path() const { return recording_path; }

void RigCapture::set_pacing(Pacing p_pacing) { pacing = p_pacing; }
RigCapture::Pacing RigCapture::get_pacing() const { return pacing; }
void RigCapture::set_loop(bool p_loop) { loop = p_loop; }
bool RigCapture::get_loop() const { return loop; }

PackedStringArray RigCapture::get_warnings() const {
	PackedStringArray warnings;
	warnings.push_back("Playback is not implemented yet (issue #3): RigCapture delivers no frames.");
	if (recording_path.is_empty()) {
		warnings.push_back("Set recording_path to a recording folder (the recording format comes with issue #3).");
	}
	return warnings;
}

void RigCapture::_bind_methods() {
	ClassDB::bind_method(D_METHOD("get_warnings"), &RigCapture::get_warnings);
	ClassDB::bind_method(D_METHOD("set_recording_path", "path"), &RigCapture::set_recording_path);
	ClassDB::bind_method(D_METHOD("get_recording_path"), &RigCapture::get_recording_path);
	ClassDB::bind_method(D_METHOD("set_pacing", "pacing"), &RigCapture::set_pacing);
	ClassDB::bind_method(D_METHOD("get_pacing"), &RigCapture::get_pacing);
	ClassDB::bind_method(D_METHOD("set_loop", "loop"), &RigCapture::set_loop);
	ClassDB::bind_method(D_METHOD("get_loop"), &RigCapture::get_loop);

	ADD_PROPERTY(PropertyInfo(Variant::STRING, "recording_path", PROPERTY_HINT_GLOBAL_DIR), "set_recording_path", "get_recording_path");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "pacing", PROPERTY_HINT_ENUM, "Real Time,Step"), "set_pacing", "get_pacing");
	ADD_PROPERTY(PropertyInfo(Variant::BOOL, "loop"), "set_loop", "get_loop");

	BIND_ENUM_CONSTANT(PACING_REAL_TIME);
	BIND_ENUM_CONSTANT(PACING_STEP);

	ADD_SIGNAL(MethodInfo("frame_captured", PropertyInfo(Variant::INT, "index"), PropertyInfo(Variant::FLOAT, "timestamp")));
	ADD_SIGNAL(MethodInfo("finished"));
}

} // namespace roomprobe
