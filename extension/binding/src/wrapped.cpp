// Wrappers of engine objects and the lifetime of RoomProbe's own instances.
#include <rp_godot/core/error_macros.h>
#include <rp_godot/core/object.h>
#include <rp_godot/gen/runtime_hashes.gen.h>

#include <string>
#include <unordered_map>

namespace godot {

namespace internal {

namespace {

thread_local PendingOwner pending;

std::unordered_map<std::string, WrapperFactory> &factories() {
	static std::unordered_map<std::string, WrapperFactory> map;
	return map;
}

// The engine's parent class of p_class, asked of its ClassDB without creating wrappers
// (this runs while a wrapper is being created).
std::string parent_class_of(const std::string &p_class) {
	static const GDExtensionMethodBindPtr mb = method_bind("ClassDB", "get_parent_class", hashes::ClassDB_get_parent_class);
	static GDExtensionObjectPtr class_db = singleton_object("ClassDB");
	StringName cls(p_class.c_str());
	StringName ret;
	const GDExtensionConstTypePtr args[] = { cls._native_ptr() };
	gdi.object_method_bind_ptrcall(mb, class_db, args, ret._native_ptr());
	return ret.utf8_string();
}

void *create_engine_wrapper(void *, void *p_object) {
	StringName cls_name;
	gdi.object_get_class_name(p_object, library, cls_name._native_ptr());
	std::string cls = cls_name.utf8_string();
	while (!cls.empty()) {
		auto it = factories().find(cls);
		if (it != factories().end()) {
			return it->second(p_object);
		}
		cls = parent_class_of(cls);
	}
	return Wrapped::_wrap<Object>(p_object);
}

void free_engine_wrapper(void *, void *, void *p_binding) {
	delete static_cast<Wrapped *>(p_binding);
}

GDExtensionBool reference_binding(void *, void *, GDExtensionBool) {
	return true;
}

const GDExtensionInstanceBindingCallbacks engine_binding_callbacks = { &create_engine_wrapper, &free_engine_wrapper, &reference_binding };
// An extension instance is freed by free_instance_func, never through its binding.
const GDExtensionInstanceBindingCallbacks extension_binding_callbacks = { nullptr, [](void *, void *, void *) {}, &reference_binding };

} // namespace

void set_pending_owner(GDExtensionObjectPtr p_owner, const char *p_extension_class) {
	pending = { p_owner, p_extension_class };
}

void register_engine_wrapper(const char *p_class, WrapperFactory p_factory) {
	factories()[p_class] = p_factory;
}

Wrapped *get_wrapper(GDExtensionObjectPtr p_owner) {
	return static_cast<Wrapped *>(gdi.object_get_instance_binding(p_owner, token, &engine_binding_callbacks));
}

GDExtensionObjectPtr construct_native(const char *p_native_class) {
	StringName cls(p_native_class);
	return gdi.classdb_construct_object2(cls._native_ptr());
}

void finish_extension_instance(Wrapped *p_instance, bool p_notify_postinitialize) {
	if (p_notify_postinitialize) {
		// Godot's own classes get NOTIFICATION_POSTINITIALIZE (0) when construction is done.
		static const GDExtensionMethodBindPtr mb = method_bind("Object", "notification", hashes::Object_notification);
		int64_t what = 0;
		GDExtensionBool reversed = false;
		const GDExtensionConstTypePtr args[] = { &what, &reversed };
		gdi.object_method_bind_ptrcall(mb, p_instance->_owner, args, nullptr);
	}
}

bool refcounted_init_ref(GDExtensionObjectPtr p_object) {
	static const GDExtensionMethodBindPtr mb = method_bind("RefCounted", "init_ref", hashes::RefCounted_init_ref);
	GDExtensionBool ret = false;
	gdi.object_method_bind_ptrcall(mb, p_object, nullptr, &ret);
	return ret;
}

bool refcounted_reference(GDExtensionObjectPtr p_object) {
	static const GDExtensionMethodBindPtr mb = method_bind("RefCounted", "reference", hashes::RefCounted_reference);
	GDExtensionBool ret = false;
	gdi.object_method_bind_ptrcall(mb, p_object, nullptr, &ret);
	return ret;
}

bool refcounted_unreference(GDExtensionObjectPtr p_object) {
	static const GDExtensionMethodBindPtr mb = method_bind("RefCounted", "unreference", hashes::RefCounted_unreference);
	GDExtensionBool ret = false;
	gdi.object_method_bind_ptrcall(mb, p_object, nullptr, &ret);
	if (ret) {
		gdi.object_destroy(p_object);
	}
	return ret;
}

} // namespace internal

Wrapped::Wrapped() {
	internal::PendingOwner p = internal::pending;
	internal::pending = {};
	_owner = p.owner;
	if (p.extension_class) {
		StringName cls(p.extension_class);
		internal::gdi.object_set_instance(_owner, cls._native_ptr(), this);
		internal::gdi.object_set_instance_binding(_owner, internal::token, this, &internal::extension_binding_callbacks);
	}
}

void memdelete(Wrapped *p_object) {
	ERR_FAIL_NULL(p_object);
	// The engine frees the object, and with it this wrapper or extension instance.
	internal::gdi.object_destroy(p_object->_owner);
}

} // namespace godot
