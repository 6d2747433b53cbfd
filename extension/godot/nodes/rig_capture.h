#pragma once
// RigCapture: where the rig's frames come from (RGB-D plus fisheye). Plays recordings now;
// live devices (extension/drivers) come later.

#include <rp_godot/godot.h>

namespace roomprobe {

class RigCapture : public godot::Node {
	GDCLASS(RigCapture, godot::Node)

public:
	enum Pacing {
		PACING_REAL_TIME, // Frames follow their timestamps.
		PACING_STEP, // One frame per request, deterministic, for tests (the stepping call comes with playback, #3).
	};

	void set_recording_path(const godot::String &p_path);
	godot::String get_recording_path() const;
	void set_pacing(Pacing p_pacing);
	Pacing get_pacing() const;
	void set_loop(bool p_loop);
	bool get_loop() const;

	// What the node cannot do as configured; the editor shows these as configuration warnings.
	godot::PackedStringArray get_warnings() const;
	godot::PackedStringArray _get_configuration_warnings() const { return get_warnings(); }

protected:
	static void _bind_methods();

private:
	godot::String recording_path;
	Pacing pacing = PACING_REAL_TIME;
	bool loop = false;
};

} // namespace roomprobe

VARIANT_ENUM_CAST(roomprobe::RigCapture::Pacing)
