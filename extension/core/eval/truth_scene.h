#pragma once
// The ground truth's geometry, for the error budget's oracles and the parallax measurement
// (issue #16): a synthetic recording's scene, rebuilt from its synth.yaml (scene name, duration,
// and the panorama it was rendered with) by the same synth/ code that rendered it, so a ray asks
// the very surfaces the frames and cubemaps show.

#include <envmap/cubemap.h>
#include <room/floorplan.h>
#include <synth/synth_renderer.h>

#include <array>
#include <memory>
#include <string>

namespace roomprobe {

struct TruthSceneResult {
	bool ok = false;
	std::string error; // names synth.yaml and the field
	std::unique_ptr<synth::SynthRenderer> renderer;
};

// Rebuilds the scene of recording folder p_recording from its synth.yaml: `scene`, `duration_s`
// and `scene_panorama` (the panorama's path or "none"; written by ./roomprobe synth since issue
// #16, and required for the two scenes that show one).
TruthSceneResult load_truth_scene(const std::string &p_recording);

// A surface point lies on the room's prism (floor, ceiling or a wall of p_floorplan) within
// p_tolerance_m: the room's shell, which the coarse model can show, rather than what stands in it.
// The default takes in what lies flat on the shell (a ceiling panel 1.5 cm below the ceiling, a
// picture, a rug): the coarse texture's business, at 2 cm texels.
bool on_prism(const Floorplan &p_floorplan, const glm::dvec3 &p_point, double p_tolerance_m = 0.03);

// For each face pixel of a p_size cubemap at p_position: 255 where the scene's first surface along
// the pixel's direction lies on the prism (on_prism), 0 where something else stands in the way
// (CV_8UC1 faces).
std::array<cv::Mat, 6> prism_directions(const synth::SynthRenderer &p_scene, const Floorplan &p_floorplan, const glm::dvec3 &p_position, int p_size);

// The distance from p_position to the scene's first surface for each face pixel (CV_32FC1 faces,
// metres; 0 where the ray hits nothing): the truth for a map's distance faces.
std::array<cv::Mat, 6> true_distances(const synth::SynthRenderer &p_scene, const glm::dvec3 &p_position, int p_size);

} // namespace roomprobe
