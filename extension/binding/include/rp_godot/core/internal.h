#pragma once
// The binding's link to the running engine: the interface table, the library handle,
// and cached look-ups of method binds. Not for use outside the binding.

#include <rp_godot/core/defs.h>
#include <rp_godot/gen/interface.gen.h>

#include <initializer_list>

namespace godot {

class Variant;
class StringName;
class Wrapped;

namespace internal {

extern InterfaceTable gdi;
extern GDExtensionClassLibraryPtr library;
// The token under which RoomProbe keeps its wrapper of each engine object.
extern void *token;

GDExtensionMethodBindPtr method_bind(const char *p_class, const char *p_method, int64_t p_hash);
GDExtensionPtrBuiltInMethod builtin_method(GDExtensionVariantType p_type, const char *p_method, int64_t p_hash);
GDExtensionPtrOperatorEvaluator operator_evaluator(GDExtensionVariantOperator p_op, GDExtensionVariantType p_left, GDExtensionVariantType p_right);
GDExtensionPtrUtilityFunction utility_function(const char *p_name, int64_t p_hash);
GDExtensionPtrConstructor builtin_constructor(GDExtensionVariantType p_type, int32_t p_index);
GDExtensionPtrDestructor builtin_destructor(GDExtensionVariantType p_type);
GDExtensionObjectPtr singleton_object(const char *p_name);

// An interned name that lives until the library is deinitialised, for comparisons on hot paths.
// p_literal must be a string literal (its address is the key).
const StringName &static_name(const char *p_literal);
void release_static_names();

Variant call_vararg(GDExtensionMethodBindPtr p_method, GDExtensionObjectPtr p_owner, std::initializer_list<Variant> p_args);
void call_utility_vararg(GDExtensionPtrUtilityFunction p_fn, Variant *r_ret, std::initializer_list<Variant> p_args);

// Wrappers of engine objects: created on first sight, as the most derived class known here.
using WrapperFactory = Wrapped *(*)(GDExtensionObjectPtr p_owner);
void register_engine_wrapper(const char *p_class, WrapperFactory p_factory);
void register_engine_wrappers(); // generated
Wrapped *get_wrapper(GDExtensionObjectPtr p_owner);
inline Wrapped *get_wrapper_or_null(GDExtensionObjectPtr p_owner) {
	return p_owner ? get_wrapper(p_owner) : nullptr;
}

template <typename T>
T *wrap(GDExtensionObjectPtr p_owner) {
	return p_owner ? static_cast<T *>(get_wrapper(p_owner)) : nullptr;
}

template <typename T>
T *singleton(const char *p_name) {
	return wrap<T>(singleton_object(p_name));
}

} // namespace internal
} // namespace godot
