// Registration of RoomProbe's classes, methods, properties and signals with the engine.
#include <rp_godot/core/class_db.h>
#include <rp_godot/core/error_macros.h>

#include <memory>
#include <vector>

namespace godot {

using internal::gdi;

namespace {
std::vector<StringName> *registered_classes = nullptr;
std::vector<std::unique_ptr<internal::MethodBindBase>> *method_binds = nullptr;
} // namespace

PropertyInfo::PropertyInfo(Variant::Type p_type, const StringName &p_name, PropertyHint p_hint, const String &p_hint_string, uint32_t p_usage, const StringName &p_class_name) :
		type(p_type), name(p_name), class_name(p_class_name), hint(uint32_t(p_hint)), hint_string(p_hint_string), usage(p_usage) {}

GDExtensionPropertyInfo PropertyInfo::native() const {
	return GDExtensionPropertyInfo{
		GDExtensionVariantType(type),
		const_cast<void *>(name._native_ptr()),
		const_cast<void *>(class_name._native_ptr()),
		hint,
		const_cast<void *>(hint_string._native_ptr()),
		usage,
	};
}

void ClassDB::_register_class(const char *p_class, const char *p_parent, GDExtensionClassCreationInfo4 &p_info) {
	if (!registered_classes) {
		registered_classes = new std::vector<StringName>();
		method_binds = new std::vector<std::unique_ptr<internal::MethodBindBase>>();
	}
	StringName cls(p_class), parent(p_parent);
	auto register_fn = gdi.classdb_register_extension_class5 ? gdi.classdb_register_extension_class5 : gdi.classdb_register_extension_class4;
	register_fn(internal::library, cls._native_ptr(), parent._native_ptr(), &p_info);
	registered_classes->push_back(cls);
}

void ClassDB::_register_method(const char *p_class, internal::MethodBindBase *p_bind, const MethodDefinition &p_definition, std::vector<Variant> p_defaults, bool p_static) {
	method_binds->emplace_back(p_bind);
	const int count = p_bind->argument_count();
	if (int(p_definition.args.size()) != count) {
		ERR_PRINT(String((std::string("bind_method: ") + p_class + "." + p_definition.name.utf8_string() + " names " +
				std::to_string(p_definition.args.size()) + " arguments but takes " + std::to_string(count)).c_str()));
		return;
	}
	p_bind->defaults = std::move(p_defaults);

	// Property infos for the return value and each argument; they must outlive the call below.
	auto info_for = [&](int p_index, const StringName &p_name) {
		const bool is_enum = p_bind->is_enum(p_index);
		uint32_t usage = uint32_t(PROPERTY_USAGE_DEFAULT) | (is_enum ? uint32_t(PROPERTY_USAGE_CLASS_IS_ENUM) : 0u);
		if (p_index < 0 && p_bind->type_of(p_index) == GDEXTENSION_VARIANT_TYPE_NIL && p_bind->has_return()) {
			usage |= PROPERTY_USAGE_NIL_IS_VARIANT;
		}
		if (p_index >= 0 && p_bind->type_of(p_index) == GDEXTENSION_VARIANT_TYPE_NIL) {
			usage |= PROPERTY_USAGE_NIL_IS_VARIANT;
		}
		return PropertyInfo(Variant::Type(p_bind->type_of(p_index)), p_name, PROPERTY_HINT_NONE, String(), usage, StringName(p_bind->class_name_of(p_index)));
	};
	PropertyInfo ret_info = info_for(-1, StringName());
	GDExtensionPropertyInfo ret_native = ret_info.native();
	std::vector<PropertyInfo> arg_infos;
	std::vector<GDExtensionPropertyInfo> arg_natives;
	std::vector<GDExtensionClassMethodArgumentMetadata> arg_meta;
	for (int i = 0; i < count; i++) {
		arg_infos.push_back(info_for(i, p_definition.args[i]));
		arg_meta.push_back(p_bind->metadata_of(i));
	}
	for (const PropertyInfo &pi : arg_infos) {
		arg_natives.push_back(pi.native());
	}
	std::vector<GDExtensionVariantPtr> defaults;
	for (Variant &d : p_bind->defaults) {
		defaults.push_back(d._native_ptr());
	}

	uint32_t flags = GDEXTENSION_METHOD_FLAGS_DEFAULT;
	if (p_static) {
		flags |= GDEXTENSION_METHOD_FLAG_STATIC;
	} else if (p_bind->is_const()) {
		flags |= GDEXTENSION_METHOD_FLAG_CONST;
	}
	GDExtensionClassMethodInfo info{};
	info.name = const_cast<void *>(p_definition.name._native_ptr());
	info.method_userdata = p_bind;
	info.call_func = p_bind->varcall_func();
	info.ptrcall_func = p_bind->ptrcall_func();
	info.method_flags = flags;
	info.has_return_value = p_bind->has_return();
	info.return_value_info = p_bind->has_return() ? &ret_native : nullptr;
	info.return_value_metadata = p_bind->metadata_of(-1);
	info.argument_count = uint32_t(count);
	info.arguments_info = arg_natives.data();
	info.arguments_metadata = arg_meta.data();
	info.default_argument_count = uint32_t(defaults.size());
	info.default_arguments = defaults.data();
	StringName cls(p_class);
	gdi.classdb_register_extension_class_method(internal::library, cls._native_ptr(), &info);
}

void ClassDB::add_property(const char *p_class, const PropertyInfo &p_info, const char *p_setter, const char *p_getter) {
	StringName cls(p_class), setter(p_setter), getter(p_getter);
	GDExtensionPropertyInfo native = p_info.native();
	gdi.classdb_register_extension_class_property(internal::library, cls._native_ptr(), &native, setter._native_ptr(), getter._native_ptr());
}

void ClassDB::add_property_group(const char *p_class, const char *p_name, const char *p_prefix) {
	StringName cls(p_class);
	String name(p_name), prefix(p_prefix);
	gdi.classdb_register_extension_class_property_group(internal::library, cls._native_ptr(), name._native_ptr(), prefix._native_ptr());
}

void ClassDB::add_property_subgroup(const char *p_class, const char *p_name, const char *p_prefix) {
	StringName cls(p_class);
	String name(p_name), prefix(p_prefix);
	gdi.classdb_register_extension_class_property_subgroup(internal::library, cls._native_ptr(), name._native_ptr(), prefix._native_ptr());
}

void ClassDB::add_signal(const char *p_class, const MethodInfo &p_signal) {
	StringName cls(p_class);
	std::vector<GDExtensionPropertyInfo> args;
	for (const PropertyInfo &pi : p_signal.arguments) {
		args.push_back(pi.native());
	}
	gdi.classdb_register_extension_class_signal(internal::library, cls._native_ptr(), p_signal.name._native_ptr(), args.data(), GDExtensionInt(args.size()));
}

void ClassDB::bind_integer_constant(const char *p_class, const char *p_enum, const char *p_name, int64_t p_value, bool p_bitfield) {
	StringName cls(p_class), enum_name(p_enum), name(p_name);
	gdi.classdb_register_extension_class_integer_constant(internal::library, cls._native_ptr(), enum_name._native_ptr(), name._native_ptr(), p_value, p_bitfield);
}

void ClassDB::deinitialize() {
	if (!registered_classes) {
		return;
	}
	for (auto it = registered_classes->rbegin(); it != registered_classes->rend(); ++it) {
		gdi.classdb_unregister_extension_class(internal::library, it->_native_ptr());
	}
	delete registered_classes;
	delete method_binds;
	registered_classes = nullptr;
	method_binds = nullptr;
}

namespace internal {

bool MethodBindBase::prepare_args(const GDExtensionConstVariantPtr *p_args, GDExtensionInt p_count, std::vector<Variant> &r_args, GDExtensionCallError *r_error) const {
	const int count = argument_count();
	const int required = count - int(defaults.size());
	if (p_count > count) {
		*r_error = { GDEXTENSION_CALL_ERROR_TOO_MANY_ARGUMENTS, 0, count };
		return false;
	}
	if (p_count < required) {
		*r_error = { GDEXTENSION_CALL_ERROR_TOO_FEW_ARGUMENTS, 0, required };
		return false;
	}
	r_args.reserve(size_t(count));
	for (int i = 0; i < count; i++) {
		const Variant &arg = i < p_count ? *static_cast<const Variant *>(p_args[i]) : defaults[size_t(i - required)];
		GDExtensionVariantType expected = type_of(i);
		GDExtensionVariantType given = GDExtensionVariantType(arg.get_type());
		if (expected != GDEXTENSION_VARIANT_TYPE_NIL && given != expected && !gdi.variant_can_convert_strict(given, expected)) {
			*r_error = { GDEXTENSION_CALL_ERROR_INVALID_ARGUMENT, i, expected };
			return false;
		}
		r_args.push_back(arg);
	}
	r_error->error = GDEXTENSION_CALL_OK;
	return true;
}

} // namespace internal
} // namespace godot
