// RoomProbe's entry point: which classes the extension registers, at which level.
#include "nodes/coarse_room_model.h"
#include "nodes/dense_slam.h"
#include "nodes/rig_capture.h"
#include "nodes/room_probe.h"
#include "nodes/surface_anchor.h"
#include "resources/prt_transfer.h"

#include <rp_godot/godot.h>

#include <opencv2/core/utils/logger.hpp>

namespace roomprobe {
extern const char *const doc_xml[];
extern const size_t doc_xml_count;
} // namespace roomprobe

namespace {

void initialize_roomprobe(GDExtensionInitializationLevel p_level) {
	if (p_level != GDEXTENSION_INITIALIZATION_SCENE) {
		return;
	}
	// OpenCV's own log lines go to std::cerr from inside a library Godot loads with
	// RTLD_DEEPBIND, and there the stream's sentry crashed Godot (issue #38: a cv::FileStorage
	// that could not open its file). Every error RoomProbe reports is its own message through
	// Godot; OpenCV's log stays silent inside the engine.
	cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
	// In pipeline order: frames, tracking, the coarse room, and the probes that read them.
	godot::ClassDB::register_class<roomprobe::RigCapture>();
	godot::ClassDB::register_class<roomprobe::DenseSLAM>();
	godot::ClassDB::register_class<roomprobe::CoarseRoomModel>();
	godot::ClassDB::register_class<roomprobe::RoomProbe>();
	// Placement of the virtual objects on the real surfaces.
	godot::ClassDB::register_class<roomprobe::SurfaceAnchor>();
	// Resources the materials read.
	godot::ClassDB::register_class<roomprobe::PRTTransfer>();
}

void uninitialize_roomprobe(GDExtensionInitializationLevel) {}

} // namespace

extern "C" GDE_EXPORT GDExtensionBool roomprobe_library_init(GDExtensionInterfaceGetProcAddress p_get_proc_address, GDExtensionClassLibraryPtr p_library, GDExtensionInitialization *r_initialization) {
	godot::ExtensionSetup setup;
	setup.minimum_level = GDEXTENSION_INITIALIZATION_SCENE;
	setup.initialize = &initialize_roomprobe;
	setup.deinitialize = &uninitialize_roomprobe;
	setup.doc_xml = roomprobe::doc_xml;
	setup.doc_xml_count = roomprobe::doc_xml_count;
	return godot::internal::initialize_library(p_get_proc_address, p_library, r_initialization, setup);
}
