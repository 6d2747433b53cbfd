// Entry point of the test-only extension that exercises the binding.
#include "binding_testbed.h"

namespace {
void initialize(GDExtensionInitializationLevel p_level) {
	if (p_level == GDEXTENSION_INITIALIZATION_SCENE) {
		godot::ClassDB::register_class<roomprobe_test::BindingTestRef>();
		godot::ClassDB::register_class<roomprobe_test::BindingTestNode>();
	}
}
} // namespace

extern "C" GDE_EXPORT GDExtensionBool roomprobe_binding_test_init(GDExtensionInterfaceGetProcAddress p_get_proc_address, GDExtensionClassLibraryPtr p_library, GDExtensionInitialization *r_initialization) {
	godot::ExtensionSetup setup;
	setup.initialize = &initialize;
	return godot::internal::initialize_library(p_get_proc_address, p_library, r_initialization, setup);
}
