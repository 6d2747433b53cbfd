#pragma once
// Registration of RoomProbe's classes with the engine: GDCLASS, methods (ptrcall and varcall),
// properties with hints, groups, signals, constants, enums and static methods.

#include <rp_godot/core/method_bind.h>
#include <rp_godot/core/type_info.h>

#include <string>
#include <vector>

namespace godot {

// Enums that RoomProbe's methods take or return: VARIANT_ENUM_CAST(Class::Enum) after the class.
#define VARIANT_ENUM_CAST(m_enum)                          \
	template <>                                            \
	struct godot::EnumName<m_enum> {                       \
		static constexpr const char *name = #m_enum;       \
	};

struct PropertyInfo {
	Variant::Type type = Variant::NIL;
	StringName name;
	StringName class_name;
	uint32_t hint = PROPERTY_HINT_NONE;
	String hint_string;
	uint32_t usage = PROPERTY_USAGE_DEFAULT;

	PropertyInfo() = default;
	PropertyInfo(Variant::Type p_type, const StringName &p_name, PropertyHint p_hint = PROPERTY_HINT_NONE, const String &p_hint_string = String(), uint32_t p_usage = PROPERTY_USAGE_DEFAULT, const StringName &p_class_name = StringName());
	// The engine's view of this info; it points into this object, which must outlive it.
	GDExtensionPropertyInfo native() const;
};

struct MethodInfo {
	StringName name;
	std::vector<PropertyInfo> arguments;
	template <typename... Args>
	MethodInfo(const char *p_name, const Args &...p_args) : name(p_name), arguments{ p_args... } {}
};

// D_METHOD("name", "arg1", ...): a method's name and its arguments' names.
struct MethodDefinition {
	StringName name;
	std::vector<StringName> args;
};
template <typename... Args>
MethodDefinition D_METHOD(const char *p_name, const Args &...p_args) {
	return MethodDefinition{ StringName(p_name), { StringName(p_args)... } };
}

class ClassDB {
public:
	// Registers T (declared with GDCLASS) and calls its static _bind_methods().
	template <typename T>
	static void register_class(bool p_abstract = false);

	template <typename M, typename... Defaults>
	static void bind_method(const MethodDefinition &p_definition, M p_method, const Defaults &...p_defaults) {
		using Bind = typename internal::MethodBindFor<M>::type;
		_register_method(internal::MethodBindClass<M>::name(), new Bind(p_method), p_definition, { Variant(p_defaults)... }, false);
	}
	template <typename F, typename... Defaults>
	static void bind_static_method(const char *p_class, const MethodDefinition &p_definition, F p_function, const Defaults &...p_defaults) {
		_register_method(p_class, new internal::StaticMethodBind(p_function), p_definition, { Variant(p_defaults)... }, true);
	}
	static void add_property(const char *p_class, const PropertyInfo &p_info, const char *p_setter, const char *p_getter);
	static void add_property_group(const char *p_class, const char *p_name, const char *p_prefix);
	static void add_property_subgroup(const char *p_class, const char *p_name, const char *p_prefix);
	static void add_signal(const char *p_class, const MethodInfo &p_signal);
	static void bind_integer_constant(const char *p_class, const char *p_enum, const char *p_name, int64_t p_value, bool p_bitfield = false);

	// Called when the library is deinitialised: unregisters in reverse order and frees the binds.
	static void deinitialize();

private:
	static void _register_class(const char *p_class, const char *p_parent, GDExtensionClassCreationInfo4 &p_info);
	static void _register_method(const char *p_class, internal::MethodBindBase *p_bind, const MethodDefinition &p_definition, std::vector<Variant> p_defaults, bool p_static);
};

namespace internal {

template <typename E>
std::string enum_short_name() {
	std::string n = EnumName<E>::name ? EnumName<E>::name : "";
	size_t p = n.rfind("::");
	return p == std::string::npos ? n : n.substr(p + 2);
}

template <typename T>
struct ExtensionCallbacks {
	static GDExtensionObjectPtr create(void *, GDExtensionBool p_notify_postinitialize) {
		return create_extension_instance<T>(p_notify_postinitialize)->_owner;
	}
	static void free(void *, GDExtensionClassInstancePtr p_instance) {
		delete static_cast<Wrapped *>(p_instance);
	}
	static GDExtensionClassCallVirtual get_virtual(void *, GDExtensionConstStringNamePtr p_name, uint32_t) {
		return T::template _get_virtual<T>(*static_cast<const StringName *>(p_name));
	}
	static void notification(GDExtensionClassInstancePtr p_instance, int32_t p_what, GDExtensionBool p_reversed) {
		static_cast<T *>(static_cast<Wrapped *>(p_instance))->_notification_chain(p_what, p_reversed != 0);
	}
};

} // namespace internal

template <typename T>
void ClassDB::register_class(bool p_abstract) {
	static_assert(T::_is_extension_class, "register_class takes classes declared with GDCLASS");
	GDExtensionClassCreationInfo4 info{};
	info.is_virtual = false;
	info.is_abstract = p_abstract;
	info.is_exposed = true;
	info.is_runtime = false; // RoomProbe's nodes run in the editor too, like tool scripts.
	info.notification_func = &internal::ExtensionCallbacks<T>::notification;
	info.create_instance_func = p_abstract ? nullptr : &internal::ExtensionCallbacks<T>::create;
	info.free_instance_func = &internal::ExtensionCallbacks<T>::free;
	info.get_virtual_func = &internal::ExtensionCallbacks<T>::get_virtual;
	_register_class(T::get_class_static(), T::BaseClass::get_class_static(), info);
	T::_bind_methods();
}

// Declares an extension class. Put it first in the class body: GDCLASS(RoomProbe, Node3D)
#define GDCLASS(m_class, m_inherits)                                                                         \
public:                                                                                                      \
	using BaseClass = m_inherits;                                                                            \
	static const char *get_class_static() { return #m_class; }                                               \
	static const char *get_native_class_static() { return m_inherits::get_native_class_static(); }           \
	static constexpr bool _is_extension_class = true;                                                        \
	void _notification_chain(int p_what, bool p_reversed) {                                                  \
		if (!p_reversed) {                                                                                   \
			m_inherits::_notification_chain(p_what, p_reversed);                                             \
		}                                                                                                    \
		if constexpr (!std::is_same_v<decltype(&m_class::_notification), decltype(&m_inherits::_notification)>) { \
			m_class::_notification(p_what);                                                                  \
		}                                                                                                    \
		if (p_reversed) {                                                                                    \
			m_inherits::_notification_chain(p_what, p_reversed);                                             \
		}                                                                                                    \
	}                                                                                                        \
                                                                                                             \
private:                                                                                                     \
	friend class ::godot::ClassDB;                                                                           \
	friend class ::godot::Wrapped;                                                                           \
	template <typename>                                                                                      \
	friend struct ::godot::internal::ExtensionCallbacks;

#define ADD_PROPERTY(m_info, m_setter, m_getter) ::godot::ClassDB::add_property(get_class_static(), m_info, m_setter, m_getter)
#define ADD_GROUP(m_name, m_prefix) ::godot::ClassDB::add_property_group(get_class_static(), m_name, m_prefix)
#define ADD_SUBGROUP(m_name, m_prefix) ::godot::ClassDB::add_property_subgroup(get_class_static(), m_name, m_prefix)
#define ADD_SIGNAL(m_info) ::godot::ClassDB::add_signal(get_class_static(), m_info)
#define BIND_CONSTANT(m_constant) ::godot::ClassDB::bind_integer_constant(get_class_static(), "", #m_constant, m_constant)
#define BIND_ENUM_CONSTANT(m_constant) \
	::godot::ClassDB::bind_integer_constant(get_class_static(), ::godot::internal::enum_short_name<decltype(m_constant)>().c_str(), #m_constant, m_constant)

} // namespace godot
