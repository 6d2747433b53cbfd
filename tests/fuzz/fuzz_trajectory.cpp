// A ground-truth or saved trajectory (rig/trajectory.h load_tum_trajectory: the recordings'
// groundtruth/*.txt, bench --save-trajectory): any bytes give a trajectory of strictly increasing,
// finite timestamps and finite, unit-rotation poses, or an error that names the file. A trajectory
// that loads saves and loads again to the same numbers.
#include "fuzz_common.h"

#include <rig/trajectory.h>

#include <glm/geometric.hpp>

using namespace roomprobe;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	const std::filesystem::path path = fuzz::scratch() / "rgb_trajectory.txt";
	fuzz::write_bytes(path, p_data, p_size);
	const TrajectoryLoadResult loaded = load_tum_trajectory(path.string());
	if (!loaded.ok) {
		fuzz::require(loaded.error.rfind(path.string(), 0) == 0, "a trajectory error names the file:", loaded.error);
		return 0;
	}
	const std::vector<TimedPose> &samples = loaded.trajectory.get_samples();
	fuzz::require(!samples.empty(), "a loaded trajectory has a pose");
	for (size_t i = 0; i < samples.size(); i++) {
		const TimedPose &s = samples[i];
		fuzz::require(std::isfinite(s.t_s) && (i == 0 || s.t_s > samples[i - 1].t_s), "timestamps are finite and increase");
		const glm::dvec3 t = s.world_from_camera.translation;
		fuzz::require(std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z), "translations are finite");
		const glm::dquat q = s.world_from_camera.rotation;
		fuzz::require(std::fabs(glm::length(q) - 1.0) < 1e-6, "rotations are unit quaternions");
	}
	const std::filesystem::path again = fuzz::scratch() / "rgb_trajectory_saved.txt";
	const std::string saved = save_tum_trajectory(again.string(), loaded.trajectory);
	fuzz::require(saved.empty(), "a loaded trajectory saves:", saved);
	const TrajectoryLoadResult reloaded = load_tum_trajectory(again.string());
	fuzz::require(reloaded.ok, "a saved trajectory loads:", reloaded.error);
	fuzz::require(reloaded.trajectory.get_samples().size() == samples.size(), "a saved trajectory keeps its poses");
	for (size_t i = 0; i < samples.size(); i++) {
		fuzz::require(reloaded.trajectory.get_samples()[i].t_s == samples[i].t_s, "a saved trajectory keeps its timestamps exactly");
	}
	return 0;
}
