#pragma once
// The paths a user gives RoomProbe's nodes (res://, user://, absolute, or a recording zipped) as
// paths on disk that the core can open. The one place for this, so that every node reads res://
// the same way in the editor, a project run from its folder and an exported app.

#include <rp_godot/godot.h>

#include <string>

namespace roomprobe {

// - An absolute path is itself.
// - res:// and user:// are the project's folders on disk when they exist there (the editor).
// - A file inside an exported pack (a rig.yaml under res://) is copied out to
//   user://roomprobe/unpacked/ once and read from there.
// - A .zip (of a recording folder, wherever it is, in a pack too) is unpacked into
//   user://roomprobe/unpacked/NAME-MD5/ once; the path is the folder inside when the zip holds one.
//   Within limits (io/zip_limits.h: 32 GiB in all, 2 GiB and 100-fold an entry, the disk's free
//   space), checked on the zip's table of contents before anything is inflated; the folder is
//   renamed into place only when whole (issue #38: a zip bomb inflated without limit).
// - A folder inside an exported pack is refused: Godot exports a recording's PNG frames only as
//   imported textures, so the zip is the way to ship one.
// "" with r_error set when the path cannot be made usable. Unpacking runs on the calling thread.
std::string disk_path_for(const godot::String &p_path, std::string *r_error);

} // namespace roomprobe
