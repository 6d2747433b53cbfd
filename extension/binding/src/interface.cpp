// The binding's link to the engine: the interface table and the cached look-ups.
#include <rp_godot/core/error_macros.h>
#include <rp_godot/core/internal.h>
#include <rp_godot/gen/utility_functions.gen.h>
#include <rp_godot/variant/variant.h>

#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace godot::internal {

InterfaceTable gdi;
GDExtensionClassLibraryPtr library = nullptr;
void *token = nullptr;

namespace {
void report_missing(const std::string &p_what) {
	std::string message = "RoomProbe's binding: the engine has no " + p_what + ". The extension was built for another Godot version.";
	gdi.print_error(message.c_str(), __FUNCTION__, __FILE__, __LINE__, false);
}
} // namespace

GDExtensionMethodBindPtr method_bind(const char *p_class, const char *p_method, int64_t p_hash) {
	StringName cls(p_class), method(p_method);
	GDExtensionMethodBindPtr mb = gdi.classdb_get_method_bind(cls._native_ptr(), method._native_ptr(), p_hash);
	if (!mb) {
		report_missing(std::string("method ") + p_class + "." + p_method + " with hash " + std::to_string(p_hash));
	}
	return mb;
}

GDExtensionPtrBuiltInMethod builtin_method(GDExtensionVariantType p_type, const char *p_method, int64_t p_hash) {
	StringName method(p_method);
	GDExtensionPtrBuiltInMethod fn = gdi.variant_get_ptr_builtin_method(p_type, method._native_ptr(), p_hash);
	if (!fn) {
		report_missing(std::string("builtin method ") + p_method + " with hash " + std::to_string(p_hash));
	}
	return fn;
}

GDExtensionPtrOperatorEvaluator operator_evaluator(GDExtensionVariantOperator p_op, GDExtensionVariantType p_left, GDExtensionVariantType p_right) {
	return gdi.variant_get_ptr_operator_evaluator(p_op, p_left, p_right);
}

GDExtensionPtrUtilityFunction utility_function(const char *p_name, int64_t p_hash) {
	StringName name(p_name);
	GDExtensionPtrUtilityFunction fn = gdi.variant_get_ptr_utility_function(name._native_ptr(), p_hash);
	if (!fn) {
		report_missing(std::string("utility function ") + p_name);
	}
	return fn;
}

GDExtensionPtrConstructor builtin_constructor(GDExtensionVariantType p_type, int32_t p_index) {
	return gdi.variant_get_ptr_constructor(p_type, p_index);
}

GDExtensionPtrDestructor builtin_destructor(GDExtensionVariantType p_type) {
	return gdi.variant_get_ptr_destructor(p_type);
}

GDExtensionObjectPtr singleton_object(const char *p_name) {
	StringName name(p_name);
	return gdi.global_get_singleton(name._native_ptr());
}

namespace {
// Held by pointer: the names must be released while the engine is still up, not at exit.
std::unordered_map<const char *, std::unique_ptr<StringName>> *static_names = nullptr;
} // namespace

const StringName &static_name(const char *p_literal) {
	if (!static_names) {
		static_names = new std::unordered_map<const char *, std::unique_ptr<StringName>>();
	}
	auto &slot = (*static_names)[p_literal];
	if (!slot) {
		slot = std::make_unique<StringName>(p_literal);
	}
	return *slot;
}

void release_static_names() {
	delete static_names;
	static_names = nullptr;
}

Variant call_vararg(GDExtensionMethodBindPtr p_method, GDExtensionObjectPtr p_owner, std::initializer_list<Variant> p_args) {
	std::vector<GDExtensionConstVariantPtr> args;
	for (const Variant &arg : p_args) {
		args.push_back(arg._native_ptr());
	}
	Variant ret;
	GDExtensionCallError error{};
	// r_ret is an uninitialised Variant on the engine's side: release ours first.
	gdi.variant_destroy(ret._native_ptr());
	gdi.object_method_bind_call(p_method, p_owner, args.data(), static_cast<GDExtensionInt>(args.size()), ret._native_ptr(), &error);
	return ret;
}

void call_utility_vararg(GDExtensionPtrUtilityFunction p_fn, Variant *r_ret, std::initializer_list<Variant> p_args) {
	std::vector<GDExtensionConstTypePtr> args;
	for (const Variant &arg : p_args) {
		args.push_back(arg._native_ptr());
	}
	p_fn(r_ret ? r_ret->_native_ptr() : nullptr, args.data(), static_cast<int32_t>(args.size()));
}

void report_error(const char *p_function, const char *p_file, int p_line, const char *p_condition, const char *p_message, bool p_warning) {
	if (p_warning) {
		gdi.print_warning_with_message(p_condition, p_message, p_function, p_file, p_line, false);
	} else {
		gdi.print_error_with_message(p_condition, p_message, p_function, p_file, p_line, false);
	}
}

void report_error(const char *p_function, const char *p_file, int p_line, const char *p_condition, const String &p_message, bool p_warning) {
	report_error(p_function, p_file, p_line, p_condition, p_message.utf8_string().c_str(), p_warning);
}

std::string dotted_enum_name(const char *p_cpp_name) {
	// "ns::Class::Enum" -> "Class.Enum": the engine knows classes by name, not by C++ namespace.
	std::string name = p_cpp_name ? p_cpp_name : "";
	size_t last = name.rfind("::");
	if (last == std::string::npos) {
		return name;
	}
	size_t before = name.rfind("::", last - 1);
	size_t start = (before == std::string::npos || last == 0) ? 0 : before + 2;
	return name.substr(start, last - start) + "." + name.substr(last + 2);
}

} // namespace godot::internal

namespace godot {

void print_line(const String &p_text) {
	UtilityFunctions::print(p_text);
}

} // namespace godot
