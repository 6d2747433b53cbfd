// The room file (recording/room_file.h load_room_file): any bytes give a room that passes
// check_room, or an error that names the file. A room that loads builds its mesh (the
// floorplan's constrained Delaunay triangulation) or says why not, without throwing.
#include "fuzz_common.h"

#include <recording/room_file.h>
#include <room/room_mesh.h>

using namespace roomprobe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	const std::filesystem::path path = fuzz::scratch() / "room.yaml";
	fuzz::write_bytes(path, p_data, p_size);
	const RoomLoadResult loaded = load_room_file(path.string());
	if (!loaded.ok) {
		fuzz::require(loaded.error.find(path.string()) != std::string::npos, "a room error names the file:", loaded.error);
		return 0;
	}
	fuzz::require(check_room(loaded.room).empty(), "a loaded room passes check_room:", check_room(loaded.room));
	const RoomMeshResult mesh = build_room_mesh(loaded.room.floorplan);
	fuzz::require(mesh.ok || !mesh.error.empty(), "a room mesh that fails says why");
	if (mesh.ok) {
		fuzz::require(!mesh.mesh.indices.empty() && mesh.mesh.atlas_width > 0 && mesh.mesh.atlas_height > 0, "a built room has triangles and an atlas");
	}
	return 0;
}
