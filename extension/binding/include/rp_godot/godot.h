#pragma once
// Everything a RoomProbe node needs from the binding.

#include <rp_godot/core/class_db.h>
#include <rp_godot/core/error_macros.h>
#include <rp_godot/core/object.h>
#include <rp_godot/gen/all_classes.gen.h>
#include <rp_godot/gen/utility_functions.gen.h>

namespace godot {

// Registers an initialiser and deinitialiser for one level, and the docs to load in the editor.
struct ExtensionSetup {
	GDExtensionInitializationLevel minimum_level = GDEXTENSION_INITIALIZATION_SCENE;
	void (*initialize)(GDExtensionInitializationLevel p_level) = nullptr;
	void (*deinitialize)(GDExtensionInitializationLevel p_level) = nullptr;
	// The class reference as XML documents (zero-terminated), loaded into the editor's help.
	const char *const *doc_xml = nullptr;
	size_t doc_xml_count = 0;
};

namespace internal {
GDExtensionBool initialize_library(GDExtensionInterfaceGetProcAddress p_get_proc_address, GDExtensionClassLibraryPtr p_library, GDExtensionInitialization *r_initialization, const ExtensionSetup &p_setup);
} // namespace internal

// Frees an object at the end of the frame, as Node.queue_free does.
void print_line(const String &p_text);

} // namespace godot
