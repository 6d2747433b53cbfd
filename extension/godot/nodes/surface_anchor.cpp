#include "surface_anchor.h"

#include "../convert/pose_convert.h"
#include "../property_checks.h"

using namespace godot;

namespace roomprobe {

void SurfaceAnchor::set_dense_slam_path(const NodePath &p_path) {
	dense_slam_path = p_path;
	update_configuration_warnings();
}

NodePath SurfaceAnchor::get_dense_slam_path() const { return dense_slam_path; }

void SurfaceAnchor::set_search_height(double p_metres) {
	search_height = property_checks::clamped("SurfaceAnchor.search_height", p_metres, 0.01, 100.0, search_height, " m");
}

double SurfaceAnchor::get_search_height() const { return search_height; }

bool SurfaceAnchor::is_placed() const { return placed; }

void SurfaceAnchor::reset() {
	placed = false;
	set_process(is_inside_tree() && !Engine::get_singleton()->is_editor_hint());
}

void SurfaceAnchor::_notification(int p_what) {
	if (p_what == NOTIFICATION_READY) {
		set_process(!placed && !Engine::get_singleton()->is_editor_hint());
	}
}

void SurfaceAnchor::_process(double p_delta) {
	(void)p_delta;
	MainThreadTimer timer(MainThreadTimer::SURFACE_ANCHOR);
	std::string unused; // get_warnings() reports it
	const std::shared_ptr<LiveRoom> engine = live_room_of(find_collaborator(*this, dense_slam_path, "DenseSLAM", "dense_slam", &unused));
	if (!engine) {
		return;
	}
	// Straight down from search_height above: the first surface of the dense model (the room's
	// floor does not count: it is where the coarse model is, not a surface seen).
	const glm::dvec3 at = to_glm(get_global_position());
	const PlacementHit hit = engine->place_ray(at + glm::dvec3(0.0, search_height, 0.0), glm::dvec3(0.0, -1.0, 0.0), search_height + 10.0);
	if (hit.surface != PlacementSurface::Dense) {
		return; // not meshed there yet: again next frame
	}
	placed = true;
	set_process(false);
	set_global_position(to_godot(hit.point));
	emit_signal("placed", to_godot(hit.point), to_godot(hit.normal));
}

PackedStringArray SurfaceAnchor::get_warnings() const {
	PackedStringArray warnings;
	std::string warning;
	const Node *slam = is_inside_tree() ? find_collaborator(*this, dense_slam_path, "DenseSLAM", "dense_slam", &warning) : nullptr;
	if (!warning.empty()) {
		warnings.push_back(String(warning.c_str()));
	} else if (is_inside_tree() && slam == nullptr) {
		warnings.push_back("No DenseSLAM in the scene: the anchor puts its children down on the surfaces DenseSLAM meshes.");
	}
	return warnings;
}

void SurfaceAnchor::_bind_methods() {
	ClassDB::bind_method(D_METHOD("set_dense_slam", "path"), &SurfaceAnchor::set_dense_slam_path);
	ClassDB::bind_method(D_METHOD("get_dense_slam"), &SurfaceAnchor::get_dense_slam_path);
	ClassDB::bind_method(D_METHOD("set_search_height", "metres"), &SurfaceAnchor::set_search_height);
	ClassDB::bind_method(D_METHOD("get_search_height"), &SurfaceAnchor::get_search_height);
	ClassDB::bind_method(D_METHOD("is_placed"), &SurfaceAnchor::is_placed);
	ClassDB::bind_method(D_METHOD("reset"), &SurfaceAnchor::reset);
	ClassDB::bind_method(D_METHOD("get_warnings"), &SurfaceAnchor::get_warnings);
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "dense_slam", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "DenseSLAM"), "set_dense_slam", "get_dense_slam");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "search_height", PROPERTY_HINT_RANGE, "0.01,100,0.01,suffix:m"), "set_search_height", "get_search_height");
	ADD_SIGNAL(MethodInfo("placed", PropertyInfo(Variant::VECTOR3, "position"), PropertyInfo(Variant::VECTOR3, "normal")));
}

} // namespace roomprobe
