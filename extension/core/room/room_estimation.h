#pragma once
// The room without a tape measure (issue #18; the paper's §1 and §4.1 measure the floorplan, the
// ceiling height and the camera's initial pose by hand, and name automatic room geometry as
// future work). From the dense model of a sweep (§4.2) and the upward fisheye:
//   1. the world frame: the floor is the lowest large horizontal plane, its normal is up, y = 0
//      on it, and the x and z axes lie along the dominant walls;
//   2. the floorplan: vertical planes fitted to the dense surface, the outermost of each
//      direction kept as walls, their lines cut into faces (segment_arrangement.h), and the
//      faces the sweep saw floor in joined into the room's polygon;
//   3. the ceiling height: the highest large downward-facing plane of the dense model, or, when
//      the RGB-D camera never saw the ceiling, the height at which the walls' top edges line up
//      with the strongest edges in the fisheye images (ceiling_from_fisheye);
//   4. a given floorplan (typed or drawn) registered to the reconstructed walls and floor.
// Every function says what it could not find instead of guessing a room.

#include "floorplan.h"

#include <camera/camera_params.h>
#include <math/pose.h>

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace roomprobe {

struct TriangleMesh;

// A piece of the dense surface: a triangle's centre, its unit normal (towards free space) and area.
struct SurfaceSample {
	glm::dvec3 position_m = glm::dvec3(0.0);
	glm::dvec3 normal = glm::dvec3(0.0);
	double area_m2 = 0.0;
};
std::vector<SurfaceSample> surface_samples(const TriangleMesh &p_mesh);

struct RoomEstimationOptions {
	double plane_tolerance_m = 0.03; // a sample within this of a plane belongs to it
	double normal_tolerance_deg = 10.0; // a sample's normal within this of a plane's belongs to it
	double floor_min_area_m2 = 0.5; // the floor: the lowest horizontal plane with this much surface seen
	double ceiling_min_area_m2 = 0.5;
	double wall_min_area_m2 = 0.3; // a vertical plane with less seen is furniture or noise
	double wall_min_width_m = 1.0; // ... and one seen narrower than this too (a wardrobe's front)
	double manhattan_snap_deg = 3.0; // wall directions this close to the dominant axes are snapped to them
	double floor_cell_m = 0.02; // the grid that records where the floor was seen (finer than a partition's thickness)
	double min_floor_seen = 0.3; // a face of the walls' arrangement with this share of floor seen is inside
	double min_ceiling_height_m = 1.8, max_ceiling_height_m = 6.0;
};

// A wall found in the dense model, in the estimated world frame (floorplan coordinates x, z).
struct WallEstimate {
	Vec2 normal; // unit, horizontal, towards the room
	double offset_m = 0.0; // the wall's points p satisfy dot(normal, p) = offset_m
	double from_m = 0.0, to_m = 0.0; // the extent seen along the wall (dot with (-normal.y, normal.x))
	double area_m2 = 0.0; // surface seen on it
	double rms_m = 0.0; // the seen surface's spread about the plane
};

enum class RoomEstimateState {
	Complete, // floorplan and ceiling height found, every wall seen
	Partial, // a room, but some of its edges were never seen (their confidence is 0) or the ceiling is unknown
	NoSurface, // no dense model
	NoFloor, // no large horizontal plane below the camera
	TooFewWalls, // the walls seen do not close a room (one wall, or walls in two directions)
};
const char *room_estimate_state_name(RoomEstimateState p_state);

struct RoomEstimate {
	RoomEstimateState state = RoomEstimateState::NoSurface;
	std::string message; // what was found, or what is missing, in a sentence
	// The estimated world (Y up, y = 0 on the floor, x and z along the walls, the origin at the
	// floorplan's bounding-box minimum) from the dense model's frame.
	Pose world_from_model;
	bool manhattan = false; // every wall within manhattan_snap_deg of the two axes
	Floorplan floorplan; // world frame; ceiling_height_m 0 when unknown
	std::string ceiling_source; // "dense model", "fisheye" (set by the caller), or "" when unknown
	// Per floorplan edge (edge i from points[i]): the share of it the sweep saw as a wall, 0 to 1.
	// 0: the edge bounds what was seen (the end of the floor seen), not a wall.
	std::vector<double> edge_confidence;
	std::vector<WallEstimate> walls; // the walls kept, world frame
	double floor_seen_m2 = 0.0;
	double floor_rms_m = 0.0; // the floor's samples about its plane
};

// Steps 1 and 2, and the ceiling when the dense model holds it. p_up_hint: roughly up in the
// model's frame (the upward fisheye's axis); the floor's normal replaces it. p_camera_positions:
// where the RGB-D camera was (model frame): the faces it passed through are inside the room.
RoomEstimate estimate_room(const std::vector<SurfaceSample> &p_samples, const glm::dvec3 &p_up_hint, const std::vector<glm::dvec3> &p_camera_positions,
		const RoomEstimationOptions &p_options = RoomEstimationOptions());

// Per floorplan edge, the share of it the walls cover (a wall on its line, facing into the room).
std::vector<double> floorplan_edge_confidence(const std::vector<Vec2> &p_points, const std::vector<WallEstimate> &p_walls);
// Removes the small steps where two pieces of one wall were placed a few centimetres apart (a
// wall the fisheye extended next to the dense model's): an edge shorter than p_max_step_m between
// two edges running the same way goes, the shorter of the two moved onto the longer's line; their
// confidence becomes the length-weighted mean. io_confidence runs with the edges.
void merge_floorplan_steps(std::vector<Vec2> *io_points, std::vector<double> *io_confidence, double p_max_step_m = 0.05);
// Moves the estimated world's origin to the floorplan's bounding-box minimum (after its edges
// moved), keeping the walls and world_from_model in step.
void rebase_room_origin(RoomEstimate *io_estimate);

// One fisheye image at its pose in the estimated world frame.
struct FisheyeView {
	cv::Mat image; // CV_8UC1, CV_8UC3 or CV_32FC3 (HDR), as recorded
	Pose world_from_fisheye;
};

struct CeilingSearch {
	bool ok = false;
	std::string message;
	double height_m = 0.0;
	// The edge strength at the best height over the median strength of the heights searched:
	// a real wall-ceiling edge stands well above 1.
	double contrast = 0.0;
	size_t views_used = 0, walls_used = 0; // the walls whose top edge was in view and showed edges
};

// Step 3 from the fisheye: the ceiling height h in [p_min_m, p_max_m] (1 cm steps, refined
// between them) at which the walls' top edges, the floorplan's edges lifted to h, project onto
// the strongest image edges: the image gradient along the wall's vertical direction, averaged
// over the views, its median along each wall (furniture along part of a wall does not count),
// each wall's profile over its own median, then the walls' mean. Only the edges seen as walls
// (confidence >= 0.3) are used when any is, and a view counts only where no other of them hides
// the point from it. Needs the floorplan and the views in one frame.
CeilingSearch ceiling_from_fisheye(const std::vector<FisheyeView> &p_views, const OmniParams &p_fisheye, const Floorplan &p_floorplan, double p_min_m,
		double p_max_m, const std::vector<double> &p_edge_confidence = {});

// Walls the RGB-D camera never saw, from the fisheye: each edge of io_floorplan with confidence
// under 0.3 (where the sweep's view ended) is moved outward, up to p_max_move_m, to where its top
// edge at the known ceiling height lines up with the strongest image edge, its corners sliding
// along the neighbouring edges. The edge must stand 5 robust standard deviations above the
// positions searched, and a view counts only where no wall seen hides the point from it. An edge
// moved gets confidence FISHEYE_WALL_CONFIDENCE; one with no clear edge stays. Returns one line
// per edge tried.
inline constexpr double FISHEYE_WALL_CONFIDENCE = 0.5;
std::vector<std::string> complete_walls_from_fisheye(const std::vector<FisheyeView> &p_views, const OmniParams &p_fisheye, Floorplan *io_floorplan,
		std::vector<double> *io_edge_confidence, double p_max_move_m = 3.0);

// Step 4: a floorplan given in its own frame, placed on the reconstructed walls: the rotation
// about Y and the translation in x, z that fit its edges to the walls' surface samples
// (p_samples in the estimated world frame).
struct FloorplanRegistration {
	bool ok = false;
	std::string message;
	Pose world_from_given; // rotation about Y, translation in x, z
	double yaw_deg = 0.0;
	double residual_rms_m = 0.0; // the wall samples that fit, about the given edges
	double inlier_share = 0.0; // of the wall samples' area, the share within 10 cm of a given edge
	bool poor = false; // a warning: residual over 3 cm or under half the walls' surface fits
};
FloorplanRegistration register_floorplan(const Floorplan &p_given, const std::vector<SurfaceSample> &p_world_samples,
		const RoomEstimationOptions &p_options = RoomEstimationOptions());

// An estimated room against the true one, both tied to the same dense-model frame (the true one by
// the recording's initial pose): the estimated corners mapped into the true world.
// A room found against the true one. Two corner errors, each corner to the nearest corner of the
// other polygon, both ways: through the frames as given (for a tracked sweep, its first camera:
// the room's shape plus the tracker's drift since), and after the best turn and shift in the floor
// plane (the room's shape alone: the "after the world frame is aligned to the true one").
struct RoomComparison {
	double corner_error_max_m = 0.0; // through the frames as given
	double corner_error_fitted_m = 0.0; // after the best turn and shift
	double ceiling_error_m = 0.0;
	double up_error_deg = 0.0;
	size_t corners = 0, true_corners = 0;
};
RoomComparison compare_rooms(const Floorplan &p_estimate, const Pose &p_estimate_world_from_model, const Floorplan &p_truth,
		const Pose &p_true_world_from_model);

// Samples mapped by a pose (positions and normals).
std::vector<SurfaceSample> transform_samples(const std::vector<SurfaceSample> &p_samples, const Pose &p_pose);

} // namespace roomprobe
