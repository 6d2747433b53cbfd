#pragma once
// ArgTraits<T>: how a C++ type that a RoomProbe method takes or returns meets the engine:
// its Variant type and class name (for the editor and GDScript), and its conversions from and
// to a Variant (varcall) and a ptrcall slot. One specialisation per kind of type.

#include <rp_godot/core/object.h>

#include <string>
#include <type_traits>

namespace godot {

template <typename T, typename = void>
struct ArgTraits;

template <typename E>
struct EnumName {
	static constexpr const char *name = nullptr;
};

namespace internal {
// "Class::Enum" -> "Class.Enum"; empty for null.
std::string dotted_enum_name(const char *p_cpp_name);
} // namespace internal

template <>
struct ArgTraits<bool> {
	static constexpr GDExtensionVariantType TYPE = GDEXTENSION_VARIANT_TYPE_BOOL;
	static constexpr GDExtensionClassMethodArgumentMetadata META = GDEXTENSION_METHOD_ARGUMENT_METADATA_NONE;
	static const char *class_name() { return ""; }
	static bool from_variant(const Variant &p_v) { return p_v.booleanize(); }
	static Variant to_variant(bool p_v) { return Variant(p_v); }
	static bool from_ptr(const void *p) { return *static_cast<const GDExtensionBool *>(p) != 0; }
	static void to_ptr(bool p_v, void *r) { *static_cast<GDExtensionBool *>(r) = p_v; }
};

template <typename T>
constexpr GDExtensionClassMethodArgumentMetadata int_meta() {
	if constexpr (std::is_signed_v<T>) {
		return sizeof(T) == 1 ? GDEXTENSION_METHOD_ARGUMENT_METADATA_INT_IS_INT8 : sizeof(T) == 2 ? GDEXTENSION_METHOD_ARGUMENT_METADATA_INT_IS_INT16 : sizeof(T) == 4 ? GDEXTENSION_METHOD_ARGUMENT_METADATA_INT_IS_INT32 : GDEXTENSION_METHOD_ARGUMENT_METADATA_INT_IS_INT64;
	} else {
		return sizeof(T) == 1 ? GDEXTENSION_METHOD_ARGUMENT_METADATA_INT_IS_UINT8 : sizeof(T) == 2 ? GDEXTENSION_METHOD_ARGUMENT_METADATA_INT_IS_UINT16 : sizeof(T) == 4 ? GDEXTENSION_METHOD_ARGUMENT_METADATA_INT_IS_UINT32 : GDEXTENSION_METHOD_ARGUMENT_METADATA_INT_IS_UINT64;
	}
}

// Integers and enums travel as int64.
template <typename T>
struct ArgTraits<T, std::enable_if_t<(std::is_integral_v<T> && !std::is_same_v<T, bool>) || std::is_enum_v<T>>> {
	static constexpr GDExtensionVariantType TYPE = GDEXTENSION_VARIANT_TYPE_INT;
	static constexpr GDExtensionClassMethodArgumentMetadata META = std::is_enum_v<T> ? GDEXTENSION_METHOD_ARGUMENT_METADATA_NONE : int_meta<std::conditional_t<std::is_enum_v<T>, int64_t, T>>();
	// For an enum declared with VARIANT_ENUM_CAST: "Class.Enum", so the editor shows its names.
	static const char *class_name() {
		if constexpr (std::is_enum_v<T>) {
			static const std::string name = internal::dotted_enum_name(EnumName<T>::name);
			return name.c_str();
		}
		return "";
	}
	static T from_variant(const Variant &p_v) { return static_cast<T>(static_cast<int64_t>(p_v)); }
	static Variant to_variant(T p_v) { return Variant(static_cast<int64_t>(p_v)); }
	static T from_ptr(const void *p) { return static_cast<T>(*static_cast<const int64_t *>(p)); }
	static void to_ptr(T p_v, void *r) { *static_cast<int64_t *>(r) = static_cast<int64_t>(p_v); }
};

// Floats travel as double.
template <typename T>
struct ArgTraits<T, std::enable_if_t<std::is_floating_point_v<T>>> {
	static constexpr GDExtensionVariantType TYPE = GDEXTENSION_VARIANT_TYPE_FLOAT;
	static constexpr GDExtensionClassMethodArgumentMetadata META = std::is_same_v<T, float> ? GDEXTENSION_METHOD_ARGUMENT_METADATA_REAL_IS_FLOAT : GDEXTENSION_METHOD_ARGUMENT_METADATA_REAL_IS_DOUBLE;
	static const char *class_name() { return ""; }
	static T from_variant(const Variant &p_v) { return static_cast<T>(static_cast<double>(p_v)); }
	static Variant to_variant(T p_v) { return Variant(static_cast<double>(p_v)); }
	static T from_ptr(const void *p) { return static_cast<T>(*static_cast<const double *>(p)); }
	static void to_ptr(T p_v, void *r) { *static_cast<double *>(r) = p_v; }
};

// Builtins other than the scalars: their ptrcall slot is the value itself.
template <typename T>
struct BuiltinArgTraits {
	static constexpr GDExtensionClassMethodArgumentMetadata META = GDEXTENSION_METHOD_ARGUMENT_METADATA_NONE;
	static const char *class_name() { return ""; }
	static T from_variant(const Variant &p_v) { return static_cast<T>(p_v); }
	static Variant to_variant(const T &p_v) { return Variant(p_v); }
	static T from_ptr(const void *p) { return *static_cast<const T *>(p); }
	// The engine's return slot holds a constructed value: assign over it.
	static void to_ptr(const T &p_v, void *r) { *static_cast<T *>(r) = p_v; }
};

#define RP_BUILTIN_ARG(m_type, m_enum) \
	template <> \
	struct ArgTraits<m_type> : BuiltinArgTraits<m_type> { static constexpr GDExtensionVariantType TYPE = GDEXTENSION_VARIANT_TYPE_##m_enum; };
RP_BUILTIN_ARG(String, STRING)
RP_BUILTIN_ARG(StringName, STRING_NAME)
RP_BUILTIN_ARG(NodePath, NODE_PATH)
RP_BUILTIN_ARG(RID, RID)
RP_BUILTIN_ARG(Callable, CALLABLE)
RP_BUILTIN_ARG(Signal, SIGNAL)
RP_BUILTIN_ARG(Dictionary, DICTIONARY)
RP_BUILTIN_ARG(Array, ARRAY)
RP_BUILTIN_ARG(PackedByteArray, PACKED_BYTE_ARRAY)
RP_BUILTIN_ARG(PackedInt32Array, PACKED_INT32_ARRAY)
RP_BUILTIN_ARG(PackedInt64Array, PACKED_INT64_ARRAY)
RP_BUILTIN_ARG(PackedFloat32Array, PACKED_FLOAT32_ARRAY)
RP_BUILTIN_ARG(PackedFloat64Array, PACKED_FLOAT64_ARRAY)
RP_BUILTIN_ARG(PackedStringArray, PACKED_STRING_ARRAY)
RP_BUILTIN_ARG(PackedVector2Array, PACKED_VECTOR2_ARRAY)
RP_BUILTIN_ARG(PackedVector3Array, PACKED_VECTOR3_ARRAY)
RP_BUILTIN_ARG(PackedColorArray, PACKED_COLOR_ARRAY)
RP_BUILTIN_ARG(PackedVector4Array, PACKED_VECTOR4_ARRAY)
RP_BUILTIN_ARG(Vector2, VECTOR2)
RP_BUILTIN_ARG(Vector2i, VECTOR2I)
RP_BUILTIN_ARG(Rect2, RECT2)
RP_BUILTIN_ARG(Rect2i, RECT2I)
RP_BUILTIN_ARG(Vector3, VECTOR3)
RP_BUILTIN_ARG(Vector3i, VECTOR3I)
RP_BUILTIN_ARG(Transform2D, TRANSFORM2D)
RP_BUILTIN_ARG(Vector4, VECTOR4)
RP_BUILTIN_ARG(Vector4i, VECTOR4I)
RP_BUILTIN_ARG(Plane, PLANE)
RP_BUILTIN_ARG(Quaternion, QUATERNION)
RP_BUILTIN_ARG(AABB, AABB)
RP_BUILTIN_ARG(Basis, BASIS)
RP_BUILTIN_ARG(Transform3D, TRANSFORM3D)
RP_BUILTIN_ARG(Projection, PROJECTION)
RP_BUILTIN_ARG(Color, COLOR)
#undef RP_BUILTIN_ARG

template <>
struct ArgTraits<Variant> {
	static constexpr GDExtensionVariantType TYPE = GDEXTENSION_VARIANT_TYPE_NIL;
	static constexpr GDExtensionClassMethodArgumentMetadata META = GDEXTENSION_METHOD_ARGUMENT_METADATA_NONE;
	static const char *class_name() { return ""; }
	static Variant from_variant(const Variant &p_v) { return p_v; }
	static Variant to_variant(const Variant &p_v) { return p_v; }
	static Variant from_ptr(const void *p) { return *static_cast<const Variant *>(p); }
	static void to_ptr(const Variant &p_v, void *r) { *static_cast<Variant *>(r) = p_v; }
};

// Objects travel as a pointer to the engine object's pointer.
template <typename T>
struct ArgTraits<T *, std::enable_if_t<std::is_base_of_v<Wrapped, T>>> {
	static constexpr GDExtensionVariantType TYPE = GDEXTENSION_VARIANT_TYPE_OBJECT;
	static constexpr GDExtensionClassMethodArgumentMetadata META = GDEXTENSION_METHOD_ARGUMENT_METADATA_NONE;
	static const char *class_name() { return T::get_class_static(); }
	static T *from_variant(const Variant &p_v) { return dynamic_cast<T *>(p_v.get_object()); }
	static Variant to_variant(T *p_v) { return Variant(static_cast<const Wrapped *>(p_v)); }
	static T *from_ptr(const void *p) { return dynamic_cast<T *>(internal::get_wrapper_or_null(*static_cast<const GDExtensionObjectPtr *>(p))); }
	static void to_ptr(T *p_v, void *r) { *static_cast<GDExtensionObjectPtr *>(r) = internal::owner_of(p_v); }
};

template <typename T>
struct ArgTraits<Ref<T>> {
	static constexpr GDExtensionVariantType TYPE = GDEXTENSION_VARIANT_TYPE_OBJECT;
	static constexpr GDExtensionClassMethodArgumentMetadata META = GDEXTENSION_METHOD_ARGUMENT_METADATA_NONE;
	static const char *class_name() { return T::get_class_static(); }
	static Ref<T> from_variant(const Variant &p_v) { return Ref<T>(p_v); }
	static Variant to_variant(const Ref<T> &p_v) { return Variant(p_v); }
	static Ref<T> from_ptr(const void *p) {
		return Ref<T>(dynamic_cast<T *>(internal::get_wrapper_or_null(internal::gdi.ref_get_object(const_cast<void *>(p)))));
	}
	static void to_ptr(const Ref<T> &p_v, void *r) { internal::gdi.ref_set_object(r, internal::owner_of(p_v.ptr())); }
};

} // namespace godot
