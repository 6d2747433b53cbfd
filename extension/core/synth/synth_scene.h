#pragma once
// Synthetic scenes for the synthetic rig (paper §5 support): plain data that synth_renderer.h
// turns into an Embree scene. Three reference scenes: the paper's Figure-4 two rooms, a convex
// living room, and a bare box room painted with a real panorama (flat walls whose only texture is
// the photograph, for the dense tracker). Conventions as in math/pose.h: world Y up, metres.
//
// Appearance model (see synth_renderer.h): radiance = emitted + albedo * (ambient + direct / pi),
// all linear RGB. Albedo comes from procedural, deliberately high-frequency textures evaluated
// in metres on each surface, so that reflections and reprojections can be judged.

#include <room/floorplan.h>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace roomprobe::synth {

using Color = glm::vec3; // linear RGB

inline constexpr double ALWAYS = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------- textures

enum class Pattern {
	Solid, // a
	Checker, // squares of scale_m, a and b
	Stripes, // bands of scale_m along u, a and b
	Bricks, // bricks scale_m high and 2 * scale_m long, tinted between a and b, light mortar
	Parquet, // planks scale_m wide and 6 * scale_m long, staggered, tinted between a and b, grain
	Noise, // three octaves of value noise of feature size scale_m, between a and b
	Tiles, // square tiles of scale_m, tinted between a and b, dark grout
};

struct Texture {
	Pattern pattern = Pattern::Solid;
	Color a = Color(0.5f);
	Color b = Color(0.5f);
	double scale_m = 0.1;
	double angle_rad = 0.0; // rotation of the pattern in the surface's (u, v) plane
	uint32_t seed = 0; // for the hashed tints and noise
};

// The albedo of a texture at surface coordinates (u, v), metres.
Color evaluate_texture(const Texture &p_texture, double p_u_m, double p_v_m);

// ---------------------------------------------------------------- panoramas

// An equirectangular linear-RGB panorama (the window's view). Direction d (world, unit) maps to
// u = 0.5 + atan2(d.x, -d.z) / (2 pi), v = acos(d.y) / pi: the image centre looks along -Z.
struct Panorama {
	int width = 0;
	int height = 0;
	std::vector<float> rgb; // row-major, 3 floats a pixel, linear
	Color lookup(const glm::dvec3 &p_direction) const; // bilinear
};

struct PanoramaLoadResult {
	bool ok = false;
	std::string error;
	std::shared_ptr<const Panorama> panorama;
};

// Reads a Radiance .hdr (io/radiance_hdr.h) or an OpenEXR's R, G, B as they are (linear), or an
// 8- or 16-bit PNG or JPEG of 3 channels as sRGB (undone approximately, gamma 2.2): told apart by
// their first bytes. Negative values and NaN become 0. The error names p_path.
PanoramaLoadResult load_panorama(const std::string &p_path);

// ---------------------------------------------------------------- materials

enum class Emission {
	None,
	Constant, // emission_scale
	Panorama, // emission_scale * scene.panorama(ray direction): a window onto a scene at infinity
	Screen, // emission_scale * screen_content(u / screen_width, v / screen_height, time)
	// emission_scale * scene.panorama(hit point - scene.panorama_center): the panorama painted on
	// the surface as seen from that point, so that from there the room looks like the photograph.
	ProjectedPanorama,
};

struct Material {
	std::string name;
	Texture albedo;
	Emission emission = Emission::None;
	Color emission_scale = Color(0.0f);
	double screen_width_m = 1.0, screen_height_m = 1.0; // Screen: the picture's size on the surface
	double on_from_s = -ALWAYS; // emission is on for on_from_s <= t < on_until_s
	double on_until_s = ALWAYS;
	bool unlit = false; // flat-lit: radiance = albedo (+ emission), no ambient or lights
};

// A screen's picture at normalised coordinates (x right, y down, in [0, 1]) and time t: colour
// bars that cycle, a hue that drifts and a bright square that moves. Linear, at most about 1.
Color screen_content(double p_x, double p_y, double p_time_s);

// ---------------------------------------------------------------- geometry

// A parallelogram corner + s * edge_u + t * edge_v, s and t in [0, 1]. Texture coordinates are
// metres from the corner along edge_u and edge_v. Seen from both sides.
struct Quad {
	glm::dvec3 corner = glm::dvec3(0.0);
	glm::dvec3 edge_u = glm::dvec3(1.0, 0.0, 0.0);
	glm::dvec3 edge_v = glm::dvec3(0.0, 1.0, 0.0);
	int material = 0;
};

// An axis-aligned box turned by yaw_rad about world Y (around its centre).
struct Box {
	glm::dvec3 center = glm::dvec3(0.0);
	glm::dvec3 half_size = glm::dvec3(0.5);
	double yaw_rad = 0.0;
	int material = 0; // sides and bottom
	int top_material = -1; // -1: material
};

struct Sphere {
	glm::dvec3 center = glm::dvec3(0.0);
	double radius = 0.1;
	int material = 0; // texture (u, v) = (longitude, latitude) in metres along the surface
};

// The floorplan prism (room/room_mesh.h), seen from inside.
struct Room {
	Floorplan floorplan;
	std::vector<int> wall_materials; // one per wall of the normalized floorplan, or one for all
	int floor_material = 0;
	int ceiling_material = 0;
};

// ---------------------------------------------------------------- lights

enum class LightKind {
	Point, // radiant intensity `power` (W/sr) from `position`
	Rect, // radiance `power` from the side cross(edge_u, edge_v) points to, sampled on a grid
};

struct Light {
	LightKind kind = LightKind::Point;
	glm::dvec3 position = glm::dvec3(0.0); // Point: the position; Rect: a corner
	glm::dvec3 edge_u = glm::dvec3(0.0), edge_v = glm::dvec3(0.0); // Rect
	Color power = Color(0.0f);
	int samples_u = 2, samples_v = 2; // Rect: fixed stratified shadow samples (noise-free)
	double shadow_skip_m = 0.0; // shadow rays stop this short of the light (its own lamp shade)
	Color ambient = Color(0.0f); // added to the scene's ambient while the light is on
	double on_from_s = -ALWAYS; // on for on_from_s <= t < on_until_s
	double on_until_s = ALWAYS;
};

inline bool is_on(double p_from_s, double p_until_s, double p_time_s) {
	return p_time_s >= p_from_s && p_time_s < p_until_s;
}

// ---------------------------------------------------------------- scenes

// How the hand-held camera of a scene's recording moves (HandheldTrajectory, synth_sequence.h).
enum class TrajectoryKind {
	Orbit, // round look_target (the table) at orbit_radius_m, looking at it
	WallSweep, // facing one wall from about wall_sweep.distance_m, sweeping sideways along it
	RoomSweep, // carried along room_sweep.path_xz, turning round: every wall, the floor and each room in view
};
const char *trajectory_name(TrajectoryKind p_kind); // "orbit", "wall_sweep", "room_sweep": synth.yaml's trajectory

struct WallSweepParams {
	glm::dvec3 wall_point = glm::dvec3(0.0); // on the wall, at the middle of the sweep (y unused)
	glm::dvec3 normal = glm::dvec3(0.0, 0.0, 1.0); // the wall's horizontal unit normal, into the room
	double half_length_m = 0.9; // the sweep goes this far either side of wall_point
	double distance_m = 1.5; // the camera's mean distance from the wall
};

// What a user does to show the rig a room (issue #18): walks a path through it, turning round
// all the time, the camera dipping to the floor and back up to the walls.
struct RoomSweepParams {
	// The floor points (x, z, metres) the rig is carried through, in order, clear of furniture
	// taller than the camera; one point: turning on the spot. Through a doorway into the next room.
	std::vector<glm::dvec2> path_xz;
	double walk_s = 10.0; // from the first point to the last, at rest at both ends; then back
	double turn_rad_s = 0.8; // the camera's yaw rate (about 1.3 turns in 10 s); its sign from the seed
	// > 0: every this many seconds the camera also tilts up to the ceiling and back (a 1.6-s
	// raised cosine, up to about 55 degrees above the horizon), as a user scanning a room with
	// one camera does (issue #43: synth --room-sweep --look-up). 0: it never looks up.
	double look_up_every_s = 0.0;
};

struct Scene {
	std::string name;
	std::vector<Material> materials;
	bool has_room = false;
	Room room;
	std::vector<Quad> quads;
	std::vector<Box> boxes;
	std::vector<Sphere> spheres;
	std::vector<Light> lights;
	Color ambient = Color(0.0f); // radiance += albedo * ambient on every lit surface
	Color background = Color(0.0f); // radiance of rays that hit nothing
	std::shared_ptr<const Panorama> panorama; // for Emission::Panorama and ProjectedPanorama; null: a procedural sky
	glm::dvec3 panorama_center = glm::dvec3(0.0); // Emission::ProjectedPanorama's point of view
	double panorama_scale = 0.0; // panorama_room: radiance = panorama_scale x panorama (0: no projected panorama)

	// Where things are, for the sequence and the tests.
	glm::dvec3 probe_position = glm::dvec3(0.0); // the ground-truth cubemaps' centre
	TrajectoryKind trajectory = TrajectoryKind::Orbit; // how the hand-held camera moves (synth_sequence.h)
	glm::dvec3 look_target = glm::dvec3(0.0); // Orbit: what the hand-held camera looks at (the table)
	double orbit_radius_m = 1.5; // Orbit: the hand-held camera's distance from look_target, horizontally
	// Orbit: > 0: one whole turn round look_target in this many seconds, in the seeded direction
	// (synth --loop: the recording comes back to where it began, for loop closure with truth);
	// 0: the seeded speed, 0.3 to 0.45 rad/s.
	double orbit_loop_s = 0.0;
	double camera_height_m = 1.45; // its mean height
	WallSweepParams wall_sweep; // WallSweep: the wall and how far from it
	RoomSweepParams room_sweep; // RoomSweep (any scene with a room: synth --room-sweep)
	glm::dvec3 ceiling_light_center = glm::dvec3(0.0); // the switched light's panel (living_room)
	double ceiling_light_half_size_m = 0.0; // its half width; 0: there is none
	double light_switch_s = ALWAYS; // when it switches on
};

struct SceneOptions {
	double duration_s = 10.0; // the ceiling light (living_room) switches on at duration_s / 2
	// The window's view (living_room; empty: a procedural sky), or the photograph the walls show
	// (panorama_room; required there).
	std::string panorama_path;
};

struct SceneResult {
	bool ok = false;
	std::string error;
	Scene scene;
};

// "two_rooms": figure4_two_rooms() with its partition, two ceiling lights, a table with objects
// near the probe in the left room, a wardrobe and a bookshelf occluding walls.
// "living_room": living_room(), a table with objects, a window showing the panorama, a screen
// whose picture changes, a floor lamp and a ceiling light that switches on half-way.
// "panorama_room": a bare 5 x 4 x 2.6 m box whose walls, floor and ceiling show the panorama as
// seen from the room's centre (unlit, scaled by panorama_exposure_scale), and a WallSweep
// trajectory in front of wall 0 (z = 0).
SceneResult make_scene(const std::string &p_name, const SceneOptions &p_options);
std::vector<std::string> scene_names();

// The scale panorama_room puts on its panorama so that 8-bit images at exposure 1 show its
// texture: PANORAMA_KEY / the panorama's log-average luminance (over the sphere, by solid angle),
// Reinhard's "key" exposure, so any HDR photograph lands mid-grey on average.
inline constexpr double PANORAMA_KEY = 0.18;
double panorama_exposure_scale(const Panorama &p_panorama);

// Adds a material and returns its index.
int add_material(Scene *r_scene, const Material &p_material);

} // namespace roomprobe::synth
