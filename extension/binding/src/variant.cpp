// Variant, and the hand-written parts of String, StringName, NodePath, Array and Dictionary.
#include <rp_godot/core/object.h>
#include <rp_godot/variant/variant.h>

#include <vector>

namespace godot {

namespace internal {
namespace {
GDExtensionVariantFromTypeConstructorFunc from_type[GDEXTENSION_VARIANT_TYPE_VARIANT_MAX];
GDExtensionTypeFromVariantConstructorFunc to_type[GDEXTENSION_VARIANT_TYPE_VARIANT_MAX];
} // namespace

void load_variant_converters() {
	for (int t = 1; t < GDEXTENSION_VARIANT_TYPE_VARIANT_MAX; t++) {
		from_type[t] = gdi.get_variant_from_type_constructor(GDExtensionVariantType(t));
		to_type[t] = gdi.get_variant_to_type_constructor(GDExtensionVariantType(t));
	}
}
} // namespace internal

using internal::gdi;

Variant::Variant() { gdi.variant_new_nil(_opaque); }
Variant::Variant(const Variant &p_other) { gdi.variant_new_copy(_opaque, p_other._opaque); }
Variant::Variant(Variant &&p_other) noexcept {
	std::memcpy(_opaque, p_other._opaque, sizeof(_opaque));
	gdi.variant_new_nil(p_other._opaque);
}
Variant::~Variant() { gdi.variant_destroy(_opaque); }

Variant &Variant::operator=(const Variant &p_other) {
	if (this != &p_other) {
		gdi.variant_destroy(_opaque);
		gdi.variant_new_copy(_opaque, p_other._opaque);
	}
	return *this;
}

Variant &Variant::operator=(Variant &&p_other) noexcept {
	if (this != &p_other) {
		uint8_t tmp[sizeof(_opaque)];
		std::memcpy(tmp, _opaque, sizeof(_opaque));
		std::memcpy(_opaque, p_other._opaque, sizeof(_opaque));
		std::memcpy(p_other._opaque, tmp, sizeof(_opaque));
	}
	return *this;
}

Variant::Variant(bool p_value) {
	GDExtensionBool v = p_value;
	internal::from_type[GDEXTENSION_VARIANT_TYPE_BOOL](_opaque, &v);
}
Variant::Variant(int64_t p_value) { internal::from_type[GDEXTENSION_VARIANT_TYPE_INT](_opaque, &p_value); }
Variant::Variant(double p_value) { internal::from_type[GDEXTENSION_VARIANT_TYPE_FLOAT](_opaque, &p_value); }
Variant::Variant(const char *p_utf8) : Variant(String(p_utf8)) {}
Variant::Variant(const Wrapped *p_object) {
	GDExtensionObjectPtr owner = internal::owner_of(p_object);
	if (!owner) {
		// A null object is Nil, as in GDScript; an Object-typed null would read as a freed object.
		gdi.variant_new_nil(_opaque);
		return;
	}
	internal::from_type[GDEXTENSION_VARIANT_TYPE_OBJECT](_opaque, &owner);
}

#define RP_VARIANT_OPAQUE(m_type, m_enum)                                                                     \
	Variant::Variant(const m_type &p_value) {                                                                 \
		internal::from_type[GDEXTENSION_VARIANT_TYPE_##m_enum](_opaque, const_cast<void *>(p_value._native_ptr())); \
	}                                                                                                         \
	Variant::operator m_type() const {                                                                        \
		m_type ret;                                                                                           \
		internal::to_type[GDEXTENSION_VARIANT_TYPE_##m_enum](ret._uninitialized_ptr(), const_cast<uint8_t *>(_opaque)); \
		return ret;                                                                                           \
	}
#define RP_VARIANT_POD(m_type, m_enum)                                                                         \
	Variant::Variant(const m_type &p_value) {                                                                  \
		internal::from_type[GDEXTENSION_VARIANT_TYPE_##m_enum](_opaque, const_cast<m_type *>(&p_value));        \
	}                                                                                                          \
	Variant::operator m_type() const {                                                                         \
		m_type ret;                                                                                            \
		internal::to_type[GDEXTENSION_VARIANT_TYPE_##m_enum](&ret, const_cast<uint8_t *>(_opaque));             \
		return ret;                                                                                            \
	}
RP_VARIANT_OPAQUE(String, STRING)
RP_VARIANT_OPAQUE(StringName, STRING_NAME)
RP_VARIANT_OPAQUE(NodePath, NODE_PATH)
RP_VARIANT_OPAQUE(godot::RID, RID)
RP_VARIANT_OPAQUE(Callable, CALLABLE)
RP_VARIANT_OPAQUE(Signal, SIGNAL)
RP_VARIANT_OPAQUE(Dictionary, DICTIONARY)
RP_VARIANT_OPAQUE(Array, ARRAY)
RP_VARIANT_OPAQUE(PackedByteArray, PACKED_BYTE_ARRAY)
RP_VARIANT_OPAQUE(PackedInt32Array, PACKED_INT32_ARRAY)
RP_VARIANT_OPAQUE(PackedInt64Array, PACKED_INT64_ARRAY)
RP_VARIANT_OPAQUE(PackedFloat32Array, PACKED_FLOAT32_ARRAY)
RP_VARIANT_OPAQUE(PackedFloat64Array, PACKED_FLOAT64_ARRAY)
RP_VARIANT_OPAQUE(PackedStringArray, PACKED_STRING_ARRAY)
RP_VARIANT_OPAQUE(PackedVector2Array, PACKED_VECTOR2_ARRAY)
RP_VARIANT_OPAQUE(PackedVector3Array, PACKED_VECTOR3_ARRAY)
RP_VARIANT_OPAQUE(PackedColorArray, PACKED_COLOR_ARRAY)
RP_VARIANT_OPAQUE(PackedVector4Array, PACKED_VECTOR4_ARRAY)
RP_VARIANT_POD(Vector2, VECTOR2)
RP_VARIANT_POD(Vector2i, VECTOR2I)
RP_VARIANT_POD(Rect2, RECT2)
RP_VARIANT_POD(Rect2i, RECT2I)
RP_VARIANT_POD(Vector3, VECTOR3)
RP_VARIANT_POD(Vector3i, VECTOR3I)
RP_VARIANT_POD(Transform2D, TRANSFORM2D)
RP_VARIANT_POD(Vector4, VECTOR4)
RP_VARIANT_POD(Vector4i, VECTOR4I)
RP_VARIANT_POD(Plane, PLANE)
RP_VARIANT_POD(Quaternion, QUATERNION)
RP_VARIANT_POD(godot::AABB, AABB)
RP_VARIANT_POD(Basis, BASIS)
RP_VARIANT_POD(Transform3D, TRANSFORM3D)
RP_VARIANT_POD(Projection, PROJECTION)
RP_VARIANT_POD(Color, COLOR)
#undef RP_VARIANT_OPAQUE
#undef RP_VARIANT_POD

// Scalars convert with the engine's own rules (e.g. a float Variant read as int truncates).
Variant::operator bool() const { return booleanize(); }
Variant::operator int64_t() const {
	if (get_type() == FLOAT) {
		return static_cast<int64_t>(operator double());
	}
	int64_t ret = 0;
	internal::to_type[GDEXTENSION_VARIANT_TYPE_INT](&ret, const_cast<uint8_t *>(_opaque));
	return ret;
}
Variant::operator double() const {
	if (get_type() == INT) {
		return static_cast<double>(operator int64_t());
	}
	double ret = 0;
	internal::to_type[GDEXTENSION_VARIANT_TYPE_FLOAT](&ret, const_cast<uint8_t *>(_opaque));
	return ret;
}

Wrapped *Variant::get_object() const {
	if (get_type() != OBJECT) {
		return nullptr;
	}
	GDExtensionObjectPtr owner = nullptr;
	internal::to_type[GDEXTENSION_VARIANT_TYPE_OBJECT](&owner, const_cast<uint8_t *>(_opaque));
	return internal::get_wrapper_or_null(owner);
}

Variant::Type Variant::get_type() const { return Type(gdi.variant_get_type(_opaque)); }
bool Variant::booleanize() const { return gdi.variant_booleanize(_opaque); }

String Variant::stringify() const {
	String ret;
	gdi.variant_stringify(_opaque, ret._uninitialized_ptr());
	return ret;
}

bool Variant::operator==(const Variant &p_other) const {
	Variant ret;
	GDExtensionBool valid = false;
	gdi.variant_evaluate(GDEXTENSION_VARIANT_OP_EQUAL, _opaque, p_other._opaque, ret._opaque, &valid);
	return valid && ret.booleanize();
}

Variant Variant::call(const StringName &p_method, std::initializer_list<Variant> p_args, GDExtensionCallError *r_error) {
	std::vector<GDExtensionConstVariantPtr> args;
	for (const Variant &a : p_args) {
		args.push_back(a._native_ptr());
	}
	Variant ret;
	gdi.variant_destroy(ret._opaque);
	GDExtensionCallError error{};
	gdi.variant_call(_opaque, p_method._native_ptr(), args.data(), GDExtensionInt(args.size()), ret._opaque, r_error ? r_error : &error);
	return ret;
}

String Variant::get_type_name(Type p_type) {
	String ret;
	gdi.variant_get_type_name(GDExtensionVariantType(p_type), ret._uninitialized_ptr());
	return ret;
}

// ---------------------------------------------------------------- String and names

String::String(const char *p_utf8) : OpaqueBuiltin(Uninitialized{}) {
	gdi.string_new_with_utf8_chars(_opaque, p_utf8 ? p_utf8 : "");
}

String::String(const char32_t *p_utf32) : OpaqueBuiltin(Uninitialized{}) {
	gdi.string_new_with_utf32_chars(_opaque, p_utf32);
}

std::string String::utf8_string() const {
	GDExtensionInt length = gdi.string_to_utf8_chars(_opaque, nullptr, 0);
	std::string out(size_t(length), '\0');
	gdi.string_to_utf8_chars(_opaque, out.data(), length);
	return out;
}

String String::operator+(const String &p_other) const {
	static const GDExtensionPtrOperatorEvaluator op = internal::operator_evaluator(GDEXTENSION_VARIANT_OP_ADD, GDEXTENSION_VARIANT_TYPE_STRING, GDEXTENSION_VARIANT_TYPE_STRING);
	String ret;
	op(_opaque, p_other._opaque, ret._opaque);
	return ret;
}

String &String::operator+=(const String &p_other) {
	gdi.string_operator_plus_eq_string(_opaque, p_other._opaque);
	return *this;
}

StringName::StringName(const char *p_utf8) : OpaqueBuiltin(Uninitialized{}) {
	gdi.string_name_new_with_utf8_chars(_opaque, p_utf8 ? p_utf8 : "");
}

std::string StringName::utf8_string() const {
	return String(*this).utf8_string();
}

NodePath::NodePath(const char *p_utf8) : NodePath(String(p_utf8)) {}

Variant &Array::operator[](int64_t p_index) {
	return *static_cast<Variant *>(gdi.array_operator_index(_opaque, p_index));
}

const Variant &Array::operator[](int64_t p_index) const {
	return *static_cast<const Variant *>(gdi.array_operator_index_const(_opaque, p_index));
}

Variant &Dictionary::operator[](const Variant &p_key) {
	return *static_cast<Variant *>(gdi.dictionary_operator_index(_opaque, p_key._native_ptr()));
}

const Variant &Dictionary::operator[](const Variant &p_key) const {
	return *static_cast<const Variant *>(gdi.dictionary_operator_index_const(_opaque, p_key._native_ptr()));
}

} // namespace godot
