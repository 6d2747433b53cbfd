#include <cstring>
// The library's entry: loads the interface, then hands each initialisation level to RoomProbe.
#include <rp_godot/godot.h>

namespace godot::internal {

namespace {
ExtensionSetup setup;

void initialize_level(void *, GDExtensionInitializationLevel p_level) {
	if (p_level == GDEXTENSION_INITIALIZATION_CORE) {
		load_variant_converters();
	}
	if (p_level == setup.minimum_level) {
		register_engine_wrappers();
	}
	if (p_level == GDEXTENSION_INITIALIZATION_EDITOR && gdi.editor_help_load_xml_from_utf8_chars_and_len) {
		for (size_t i = 0; i < setup.doc_xml_count; i++) {
			const char *xml = setup.doc_xml[i];
			gdi.editor_help_load_xml_from_utf8_chars_and_len(xml, GDExtensionInt(std::strlen(xml)));
		}
	}
	if (setup.initialize) {
		setup.initialize(p_level);
	}
}

void deinitialize_level(void *, GDExtensionInitializationLevel p_level) {
	if (setup.deinitialize) {
		setup.deinitialize(p_level);
	}
	if (p_level == setup.minimum_level) {
		ClassDB::deinitialize();
		release_static_names();
	}
}
} // namespace

GDExtensionBool initialize_library(GDExtensionInterfaceGetProcAddress p_get_proc_address, GDExtensionClassLibraryPtr p_library, GDExtensionInitialization *r_initialization, const ExtensionSetup &p_setup) {
	load_interface_table(p_get_proc_address, gdi);
	library = p_library;
	token = p_library;
	setup = p_setup;
	// Variant conversions are needed from the first level on, whichever RoomProbe asks for.
	r_initialization->minimum_initialization_level = GDEXTENSION_INITIALIZATION_CORE;
	r_initialization->userdata = nullptr;
	r_initialization->initialize = &initialize_level;
	r_initialization->deinitialize = &deinitialize_level;
	return true;
}

} // namespace godot::internal
