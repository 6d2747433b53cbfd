#pragma once
// Variant: Godot's tagged value, 24 bytes whose content the engine manages.

#include <rp_godot/gen/builtins.gen.h>
#include <rp_godot/gen/global_enums.gen.h>

#include <string>
#include <type_traits>

namespace godot {

class Wrapped;
template <typename T>
class Ref;

class Variant {
public:
	enum Type : int64_t {
		NIL, BOOL, INT, FLOAT, STRING, VECTOR2, VECTOR2I, RECT2, RECT2I, VECTOR3, VECTOR3I,
		TRANSFORM2D, VECTOR4, VECTOR4I, PLANE, QUATERNION, AABB, BASIS, TRANSFORM3D, PROJECTION,
		COLOR, STRING_NAME, NODE_PATH, RID, OBJECT, CALLABLE, SIGNAL, DICTIONARY, ARRAY,
		PACKED_BYTE_ARRAY, PACKED_INT32_ARRAY, PACKED_INT64_ARRAY, PACKED_FLOAT32_ARRAY,
		PACKED_FLOAT64_ARRAY, PACKED_STRING_ARRAY, PACKED_VECTOR2_ARRAY, PACKED_VECTOR3_ARRAY,
		PACKED_COLOR_ARRAY, PACKED_VECTOR4_ARRAY, VARIANT_MAX
	};

	Variant();
	Variant(const Variant &p_other);
	Variant(Variant &&p_other) noexcept;
	~Variant();
	Variant &operator=(const Variant &p_other);
	Variant &operator=(Variant &&p_other) noexcept;

	Variant(bool p_value);
	Variant(int64_t p_value);
	template <typename T, std::enable_if_t<std::is_integral_v<T> && !std::is_same_v<T, bool> && !std::is_same_v<T, int64_t>, int> = 0>
	Variant(T p_value) : Variant(static_cast<int64_t>(p_value)) {}
	template <typename T, std::enable_if_t<std::is_enum_v<T>, int> = 0>
	Variant(T p_value) : Variant(static_cast<int64_t>(p_value)) {}
	Variant(double p_value);
	Variant(float p_value) : Variant(static_cast<double>(p_value)) {}
	Variant(const char *p_utf8);
	Variant(const std::string &p_utf8) : Variant(p_utf8.c_str()) {}
	Variant(const Wrapped *p_object);
	template <typename T>
	Variant(const Ref<T> &p_ref) : Variant(static_cast<const Wrapped *>(p_ref.ptr())) {}

#define RP_VARIANT_TYPE(m_type) \
	Variant(const m_type &p_value); \
	operator m_type() const;
	RP_VARIANT_TYPE(String)
	RP_VARIANT_TYPE(StringName)
	RP_VARIANT_TYPE(NodePath)
	RP_VARIANT_TYPE(godot::RID)
	RP_VARIANT_TYPE(Callable)
	RP_VARIANT_TYPE(Signal)
	RP_VARIANT_TYPE(Dictionary)
	RP_VARIANT_TYPE(Array)
	RP_VARIANT_TYPE(PackedByteArray)
	RP_VARIANT_TYPE(PackedInt32Array)
	RP_VARIANT_TYPE(PackedInt64Array)
	RP_VARIANT_TYPE(PackedFloat32Array)
	RP_VARIANT_TYPE(PackedFloat64Array)
	RP_VARIANT_TYPE(PackedStringArray)
	RP_VARIANT_TYPE(PackedVector2Array)
	RP_VARIANT_TYPE(PackedVector3Array)
	RP_VARIANT_TYPE(PackedColorArray)
	RP_VARIANT_TYPE(PackedVector4Array)
	RP_VARIANT_TYPE(Vector2)
	RP_VARIANT_TYPE(Vector2i)
	RP_VARIANT_TYPE(Rect2)
	RP_VARIANT_TYPE(Rect2i)
	RP_VARIANT_TYPE(Vector3)
	RP_VARIANT_TYPE(Vector3i)
	RP_VARIANT_TYPE(Transform2D)
	RP_VARIANT_TYPE(Vector4)
	RP_VARIANT_TYPE(Vector4i)
	RP_VARIANT_TYPE(Plane)
	RP_VARIANT_TYPE(Quaternion)
	RP_VARIANT_TYPE(godot::AABB)
	RP_VARIANT_TYPE(Basis)
	RP_VARIANT_TYPE(Transform3D)
	RP_VARIANT_TYPE(Projection)
	RP_VARIANT_TYPE(Color)
#undef RP_VARIANT_TYPE

	operator bool() const;
	operator int64_t() const;
	operator int32_t() const { return static_cast<int32_t>(operator int64_t()); }
	operator double() const;
	operator float() const { return static_cast<float>(operator double()); }
	// The object held, or null. Its wrapper is created on first sight.
	Wrapped *get_object() const;

	Type get_type() const;
	bool booleanize() const;
	String stringify() const;
	bool operator==(const Variant &p_other) const;
	bool operator!=(const Variant &p_other) const { return !(*this == p_other); }
	// Calls a method by name, as GDScript would.
	Variant call(const StringName &p_method, std::initializer_list<Variant> p_args, GDExtensionCallError *r_error = nullptr);
	static String get_type_name(Type p_type);

	GDExtensionVariantPtr _native_ptr() { return _opaque; }
	GDExtensionConstVariantPtr _native_ptr() const { return _opaque; }

private:
	alignas(8) uint8_t _opaque[24];
};

namespace internal {
void load_variant_converters();
} // namespace internal

} // namespace godot
