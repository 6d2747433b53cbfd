#pragma once
// Classes that exercise every part of RoomProbe's binding from GDScript
// (tests/godot/test_binding_*.gd). Built into a separate test-only extension.

#include <rp_godot/godot.h>

namespace roomprobe_test {

// A RefCounted extension class: its lifetime is checked through live_count().
class BindingTestRef : public godot::RefCounted {
	GDCLASS(BindingTestRef, godot::RefCounted)

public:
	BindingTestRef() { live++; }
	~BindingTestRef() override { live--; }
	static int64_t live_count() { return live; }
	void set_value(int64_t p_value) { value = p_value; }
	int64_t get_value() const { return value; }

protected:
	static void _bind_methods();

private:
	static inline int64_t live = 0;
	int64_t value = 0;
};

class BindingTestNode : public godot::Node3D {
	GDCLASS(BindingTestNode, godot::Node3D)

public:
	enum Mode {
		MODE_OFF,
		MODE_ON = 5,
	};
	static constexpr int64_t ANSWER = 42;

	BindingTestNode() { live++; }
	~BindingTestNode() override { live--; }
	static int64_t live_count() { return live; }

	// Round trips: each returns its argument, so GDScript can compare.
	bool echo_bool(bool p_v) { return p_v; }
	int64_t echo_int(int64_t p_v) { return p_v; }
	int32_t echo_int32(int32_t p_v) { return p_v; }
	uint8_t echo_uint8(uint8_t p_v) { return p_v; }
	double echo_float(double p_v) { return p_v; }
	float echo_float32(float p_v) { return p_v; }
	godot::String echo_string(const godot::String &p_v) { return p_v; }
	godot::StringName echo_string_name(const godot::StringName &p_v) { return p_v; }
	godot::NodePath echo_node_path(const godot::NodePath &p_v) { return p_v; }
	godot::Vector2 echo_vector2(const godot::Vector2 &p_v) { return p_v; }
	godot::Vector2i echo_vector2i(const godot::Vector2i &p_v) { return p_v; }
	godot::Rect2 echo_rect2(const godot::Rect2 &p_v) { return p_v; }
	godot::Rect2i echo_rect2i(const godot::Rect2i &p_v) { return p_v; }
	godot::Vector3 echo_vector3(const godot::Vector3 &p_v) { return p_v; }
	godot::Vector3i echo_vector3i(const godot::Vector3i &p_v) { return p_v; }
	godot::Transform2D echo_transform2d(const godot::Transform2D &p_v) { return p_v; }
	godot::Vector4 echo_vector4(const godot::Vector4 &p_v) { return p_v; }
	godot::Vector4i echo_vector4i(const godot::Vector4i &p_v) { return p_v; }
	godot::Plane echo_plane(const godot::Plane &p_v) { return p_v; }
	godot::Quaternion echo_quaternion(const godot::Quaternion &p_v) { return p_v; }
	godot::AABB echo_aabb(const godot::AABB &p_v) { return p_v; }
	godot::Basis echo_basis(const godot::Basis &p_v) { return p_v; }
	godot::Transform3D echo_transform3d(const godot::Transform3D &p_v) { return p_v; }
	godot::Projection echo_projection(const godot::Projection &p_v) { return p_v; }
	godot::Color echo_color(const godot::Color &p_v) { return p_v; }
	godot::RID echo_rid(const godot::RID &p_v) { return p_v; }
	godot::Callable echo_callable(const godot::Callable &p_v) { return p_v; }
	godot::Signal echo_signal(const godot::Signal &p_v) { return p_v; }
	godot::Dictionary echo_dictionary(const godot::Dictionary &p_v) { return p_v; }
	godot::Array echo_array(const godot::Array &p_v) { return p_v; }
	godot::PackedByteArray echo_packed_byte_array(const godot::PackedByteArray &p_v) { return p_v; }
	godot::PackedInt32Array echo_packed_int32_array(const godot::PackedInt32Array &p_v) { return p_v; }
	godot::PackedInt64Array echo_packed_int64_array(const godot::PackedInt64Array &p_v) { return p_v; }
	godot::PackedFloat32Array echo_packed_float32_array(const godot::PackedFloat32Array &p_v) { return p_v; }
	godot::PackedFloat64Array echo_packed_float64_array(const godot::PackedFloat64Array &p_v) { return p_v; }
	godot::PackedStringArray echo_packed_string_array(const godot::PackedStringArray &p_v) { return p_v; }
	godot::PackedVector2Array echo_packed_vector2_array(const godot::PackedVector2Array &p_v) { return p_v; }
	godot::PackedVector3Array echo_packed_vector3_array(const godot::PackedVector3Array &p_v) { return p_v; }
	godot::PackedColorArray echo_packed_color_array(const godot::PackedColorArray &p_v) { return p_v; }
	godot::PackedVector4Array echo_packed_vector4_array(const godot::PackedVector4Array &p_v) { return p_v; }
	godot::Variant echo_variant(const godot::Variant &p_v) { return p_v; }
	godot::Node *echo_node(godot::Node *p_v) { return p_v; }
	godot::Ref<godot::Resource> echo_resource(const godot::Ref<godot::Resource> &p_v) { return p_v; }
	Mode echo_mode(Mode p_v) { return p_v; }

	// Work done in C++ on values that came from GDScript, so both directions are exercised.
	godot::PackedVector3Array scale_points(const godot::PackedVector3Array &p_points, double p_factor) const;
	godot::String describe(const godot::Dictionary &p_dict) const;
	int64_t sum_with_defaults(int64_t p_a, int64_t p_b = 7, const godot::String &p_suffix = "abc") const { return p_a + p_b + p_suffix.length(); }
	static int64_t add_static(int64_t p_a, int64_t p_b) { return p_a + p_b; }
	int64_t count_children_of(godot::Node *p_node) const { return p_node ? p_node->get_child_count() : -1; }
	godot::Variant call_on(godot::Object *p_target, const godot::StringName &p_method, const godot::Variant &p_arg) const;
	godot::Ref<BindingTestRef> make_ref(int64_t p_value) const;
	godot::Ref<godot::Image> make_image(int32_t p_width, int32_t p_height) const;
	void fire(int64_t p_value, const godot::String &p_text) { emit_signal("fired", p_value, p_text); }

	void set_speed(double p_v) { speed = p_v; }
	double get_speed() const { return speed; }
	void set_mode(Mode p_v) { mode = p_v; }
	Mode get_mode() const { return mode; }
	void set_config_file(const godot::String &p_v) { config_file = p_v; }
	godot::String get_config_file() const { return config_file; }
	void set_resource(const godot::Ref<godot::Resource> &p_v) { resource = p_v; }
	godot::Ref<godot::Resource> get_resource() const { return resource; }

	// Counts of the engine's calls into the virtual overrides below.
	godot::Dictionary get_virtual_calls() const;

	void _ready();
	void _process(double p_delta);
	void _physics_process(double p_delta);
	void _enter_tree();
	void _exit_tree();
	godot::PackedStringArray _get_configuration_warnings() const;

protected:
	static void _bind_methods();
	void _notification(int p_what);

private:
	static inline int64_t live = 0;
	double speed = 1.5;
	Mode mode = MODE_OFF;
	godot::String config_file;
	godot::Ref<godot::Resource> resource;
	int64_t ready_calls = 0, process_calls = 0, physics_calls = 0, enter_calls = 0, exit_calls = 0, ready_notifications = 0;
	double last_delta = 0.0;
};

} // namespace roomprobe_test

VARIANT_ENUM_CAST(roomprobe_test::BindingTestNode::Mode)
