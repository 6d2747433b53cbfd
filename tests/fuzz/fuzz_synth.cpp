// A synthetic recording's synth.yaml, through both public loaders that read it: the rig's
// photometry it states (rig/photometry.h read_recording_photometry, which RigCapture, eval and
// bench use) and the true scene rebuilt from it (eval/truth_scene.h load_truth_scene, the error
// budget's oracles). Any bytes give a result or an error that names synth.yaml; a photometry that
// loads passes check_photometry; a scene that loads has a renderer that works.
#include "fuzz_common.h"

#include <eval/truth_scene.h>
#include <rig/photometry.h>

using namespace roomprobe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	const std::filesystem::path folder = fuzz::scratch() / "synth";
	std::filesystem::create_directories(folder);
	const std::filesystem::path path = folder / "synth.yaml";
	fuzz::write_bytes(path, p_data, p_size);

	RigPhotometry photometry;
	std::string error;
	if (!read_recording_photometry(folder.string(), RigPhotometry(), &photometry, &error)) {
		fuzz::require(error.rfind(path.string(), 0) == 0, "a synth.yaml photometry error names the file:", error);
	} else {
		fuzz::require(error.empty(), "a photometry that loads gives no error:", error);
		fuzz::require(photometry.known, "a synth.yaml that loads states the photometry");
		fuzz::require(check_photometry(photometry).empty(), "a synth.yaml photometry passes check_photometry:", check_photometry(photometry));
	}

	const TruthSceneResult scene = load_truth_scene(folder.string());
	if (!scene.ok) {
		fuzz::require(scene.error.rfind(path.string(), 0) == 0, "a synth.yaml scene error names the file:", scene.error);
		fuzz::require(scene.renderer == nullptr, "a scene that fails has no renderer");
	} else {
		fuzz::require(scene.renderer != nullptr && scene.renderer->ok(), "a scene that loads renders:", scene.renderer ? scene.renderer->error() : "");
	}
	return 0;
}
