#pragma once
// Wrapped: the C++ side of one engine object. Engine classes are wrapped on first sight;
// RoomProbe's own classes (GDCLASS) are themselves the engine object's extension instance.

#include <rp_godot/core/internal.h>
#include <rp_godot/variant/variant.h>

#include <type_traits>

namespace godot {

class Wrapped {
public:
	// The engine object this wraps. Never null once constructed.
	GDExtensionObjectPtr _owner = nullptr;

	virtual ~Wrapped() = default;
	Wrapped(const Wrapped &) = delete;
	Wrapped &operator=(const Wrapped &) = delete;

	static const char *get_class_static() { return "Object"; }
	template <typename T>
	static Wrapped *_wrap(GDExtensionObjectPtr p_owner);

	// Extension classes chain their _notification calls through this (see GDCLASS).
	void _notification_chain(int, bool) {}
	void _notification(int) {}

protected:
	// Takes the owner that the creating code prepared (internal::pending_owner).
	Wrapped();
};

namespace internal {

inline GDExtensionObjectPtr owner_of(const Wrapped *p_wrapped) {
	return p_wrapped ? p_wrapped->_owner : nullptr;
}

// What the next Wrapped constructor binds to: an existing engine object, and for an
// extension instance, the extension class name under which it registers itself.
struct PendingOwner {
	GDExtensionObjectPtr owner = nullptr;
	const char *extension_class = nullptr;
};
void set_pending_owner(GDExtensionObjectPtr p_owner, const char *p_extension_class);

// Creates the engine object of T's native class and T's instance on it.
GDExtensionObjectPtr construct_native(const char *p_native_class);
void finish_extension_instance(Wrapped *p_instance, bool p_notify_postinitialize);

template <typename T>
T *create_extension_instance(bool p_notify_postinitialize) {
	set_pending_owner(construct_native(T::get_native_class_static()), T::get_class_static());
	T *instance = new T();
	finish_extension_instance(instance, p_notify_postinitialize);
	return instance;
}

} // namespace internal

template <typename T>
Wrapped *Wrapped::_wrap(GDExtensionObjectPtr p_owner) {
	internal::set_pending_owner(p_owner, nullptr);
	return new T();
}

// The declarations every generated engine class starts with.
#define RP_ENGINE_CLASS(m_class, m_inherits)                           \
public:                                                                \
	using BaseClass = m_inherits;                                      \
	static const char *get_class_static() { return #m_class; }         \
	static const char *get_native_class_static() { return #m_class; }  \
	static constexpr bool _is_extension_class = false;                 \
                                                                       \
protected:                                                             \
	friend class ::godot::Wrapped;                                     \
	m_class() = default;

// Creates an object of an extension or engine class, as Godot's memnew does.
template <typename T>
T *memnew_object() {
	if constexpr (T::_is_extension_class) {
		return internal::create_extension_instance<T>(true);
	} else {
		return internal::wrap<T>(internal::construct_native(T::get_class_static()));
	}
}
#define memnew(m_class) ::godot::memnew_object<m_class>()

// Frees an object that is not owned by the scene tree or a Ref.
void memdelete(Wrapped *p_object);

} // namespace godot
