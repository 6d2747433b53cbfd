// The rig file (rig/rig.h load_rig): any bytes give a rig that passes check_rig, or an error that
// names the file. A rig that loads saves and loads again to the same numbers.
#include "fuzz_common.h"

#include <rig/rig.h>

using namespace roomprobe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	const std::filesystem::path path = fuzz::scratch() / "rig.yaml";
	fuzz::write_bytes(path, p_data, p_size);
	const RigLoadResult loaded = load_rig(path.string());
	if (!loaded.ok) {
		fuzz::require(loaded.error.rfind(path.string(), 0) == 0, "a rig error names the file:", loaded.error);
		return 0;
	}
	fuzz::require(check_rig(loaded.rig).empty(), "a loaded rig passes check_rig:", check_rig(loaded.rig));
	const std::filesystem::path again = fuzz::scratch() / "rig_saved.yaml";
	const std::string saved = save_rig(again.string(), loaded.rig);
	fuzz::require(saved.empty(), "a loaded rig saves:", saved);
	const RigLoadResult reloaded = load_rig(again.string());
	fuzz::require(reloaded.ok, "a saved rig loads:", reloaded.error);
	fuzz::require(reloaded.rig.rgb.width == loaded.rig.rgb.width && reloaded.rig.fisheye.height == loaded.rig.fisheye.height &&
					reloaded.rig.depth_scale_m == loaded.rig.depth_scale_m,
			"a rig saved and loaded again keeps its numbers");
	return 0;
}
