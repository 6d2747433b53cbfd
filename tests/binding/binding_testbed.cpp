#include "binding_testbed.h"

using namespace godot;

namespace roomprobe_test {

void BindingTestRef::_bind_methods() {
	ClassDB::bind_method(D_METHOD("set_value", "value"), &BindingTestRef::set_value);
	ClassDB::bind_method(D_METHOD("get_value"), &BindingTestRef::get_value);
	ClassDB::bind_static_method("BindingTestRef", D_METHOD("live_count"), &BindingTestRef::live_count);
	ADD_PROPERTY(PropertyInfo(Variant::INT, "value"), "set_value", "get_value");
}

PackedVector3Array BindingTestNode::scale_points(const PackedVector3Array &p_points, double p_factor) const {
	PackedVector3Array out = p_points;
	for (int64_t i = 0; i < out.size(); i++) {
		out[i] = out[i] * real_t(p_factor);
	}
	return out;
}

String BindingTestNode::describe(const Dictionary &p_dict) const {
	String out;
	Array keys = p_dict.keys();
	keys.sort();
	for (int64_t i = 0; i < keys.size(); i++) {
		out += keys[i].stringify() + "=" + p_dict[keys[i]].stringify() + ";";
	}
	return out;
}

Variant BindingTestNode::call_on(Object *p_target, const StringName &p_method, const Variant &p_arg) const {
	ERR_FAIL_NULL_V(p_target, Variant());
	return p_target->call(p_method, p_arg);
}

Ref<BindingTestRef> BindingTestNode::make_ref(int64_t p_value) const {
	Ref<BindingTestRef> r;
	r.instantiate();
	r->set_value(p_value);
	return r;
}

Ref<Image> BindingTestNode::make_image(int32_t p_width, int32_t p_height) const {
	Ref<Image> image = Image::create_empty(p_width, p_height, false, Image::FORMAT_RGBA8);
	image->fill(Color(1, 0, 0, 1));
	return image;
}

Dictionary BindingTestNode::get_virtual_calls() const {
	Dictionary d;
	d["ready"] = ready_calls;
	d["process"] = process_calls;
	d["physics_process"] = physics_calls;
	d["enter_tree"] = enter_calls;
	d["exit_tree"] = exit_calls;
	d["notification_ready"] = ready_notifications;
	d["last_delta"] = last_delta;
	return d;
}

void BindingTestNode::_ready() {
	ready_calls++;
	set_process(true);
	set_physics_process(true);
}

void BindingTestNode::_process(double p_delta) {
	process_calls++;
	last_delta = p_delta;
}

void BindingTestNode::_physics_process(double) { physics_calls++; }
void BindingTestNode::_enter_tree() { enter_calls++; }
void BindingTestNode::_exit_tree() { exit_calls++; }

PackedStringArray BindingTestNode::_get_configuration_warnings() const {
	PackedStringArray w;
	if (speed <= 0) {
		w.push_back("speed must be positive");
	}
	return w;
}

void BindingTestNode::_notification(int p_what) {
	if (p_what == NOTIFICATION_READY) {
		ready_notifications++;
	}
}

void BindingTestNode::_bind_methods() {
#define ECHO(m_name) ClassDB::bind_method(D_METHOD(#m_name, "value"), &BindingTestNode::m_name)
	ECHO(echo_bool);
	ECHO(echo_int);
	ECHO(echo_int32);
	ECHO(echo_uint8);
	ECHO(echo_float);
	ECHO(echo_float32);
	ECHO(echo_string);
	ECHO(echo_string_name);
	ECHO(echo_node_path);
	ECHO(echo_vector2);
	ECHO(echo_vector2i);
	ECHO(echo_rect2);
	ECHO(echo_rect2i);
	ECHO(echo_vector3);
	ECHO(echo_vector3i);
	ECHO(echo_transform2d);
	ECHO(echo_vector4);
	ECHO(echo_vector4i);
	ECHO(echo_plane);
	ECHO(echo_quaternion);
	ECHO(echo_aabb);
	ECHO(echo_basis);
	ECHO(echo_transform3d);
	ECHO(echo_projection);
	ECHO(echo_color);
	ECHO(echo_rid);
	ECHO(echo_callable);
	ECHO(echo_signal);
	ECHO(echo_dictionary);
	ECHO(echo_array);
	ECHO(echo_packed_byte_array);
	ECHO(echo_packed_int32_array);
	ECHO(echo_packed_int64_array);
	ECHO(echo_packed_float32_array);
	ECHO(echo_packed_float64_array);
	ECHO(echo_packed_string_array);
	ECHO(echo_packed_vector2_array);
	ECHO(echo_packed_vector3_array);
	ECHO(echo_packed_color_array);
	ECHO(echo_packed_vector4_array);
	ECHO(echo_variant);
	ECHO(echo_node);
	ECHO(echo_resource);
	ECHO(echo_mode);
#undef ECHO
	ClassDB::bind_method(D_METHOD("scale_points", "points", "factor"), &BindingTestNode::scale_points);
	ClassDB::bind_method(D_METHOD("describe", "dict"), &BindingTestNode::describe);
	ClassDB::bind_method(D_METHOD("sum_with_defaults", "a", "b", "suffix"), &BindingTestNode::sum_with_defaults, 7, "abc");
	ClassDB::bind_static_method("BindingTestNode", D_METHOD("add_static", "a", "b"), &BindingTestNode::add_static);
	ClassDB::bind_static_method("BindingTestNode", D_METHOD("live_count"), &BindingTestNode::live_count);
	ClassDB::bind_method(D_METHOD("count_children_of", "node"), &BindingTestNode::count_children_of);
	ClassDB::bind_method(D_METHOD("call_on", "target", "method", "arg"), &BindingTestNode::call_on);
	ClassDB::bind_method(D_METHOD("make_ref", "value"), &BindingTestNode::make_ref);
	ClassDB::bind_method(D_METHOD("make_image", "width", "height"), &BindingTestNode::make_image);
	ClassDB::bind_method(D_METHOD("fire", "value", "text"), &BindingTestNode::fire);
	ClassDB::bind_method(D_METHOD("get_virtual_calls"), &BindingTestNode::get_virtual_calls);

	ClassDB::bind_method(D_METHOD("set_speed", "speed"), &BindingTestNode::set_speed);
	ClassDB::bind_method(D_METHOD("get_speed"), &BindingTestNode::get_speed);
	ClassDB::bind_method(D_METHOD("set_mode", "mode"), &BindingTestNode::set_mode);
	ClassDB::bind_method(D_METHOD("get_mode"), &BindingTestNode::get_mode);
	ClassDB::bind_method(D_METHOD("set_config_file", "path"), &BindingTestNode::set_config_file);
	ClassDB::bind_method(D_METHOD("get_config_file"), &BindingTestNode::get_config_file);
	ClassDB::bind_method(D_METHOD("set_resource", "resource"), &BindingTestNode::set_resource);
	ClassDB::bind_method(D_METHOD("get_resource"), &BindingTestNode::get_resource);

	ADD_GROUP("Motion", "");
	ADD_PROPERTY(PropertyInfo(Variant::FLOAT, "speed", PROPERTY_HINT_RANGE, "0,10,0.5,suffix:m/s"), "set_speed", "get_speed");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "mode", PROPERTY_HINT_ENUM, "Off:0,On:5"), "set_mode", "get_mode");
	ADD_SUBGROUP("Files", "");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "config_file", PROPERTY_HINT_FILE, "*.yaml"), "set_config_file", "get_config_file");
	ADD_PROPERTY(PropertyInfo(Variant::OBJECT, "resource", PROPERTY_HINT_RESOURCE_TYPE, "Resource"), "set_resource", "get_resource");

	BIND_CONSTANT(ANSWER);
	BIND_ENUM_CONSTANT(MODE_OFF);
	BIND_ENUM_CONSTANT(MODE_ON);

	ADD_SIGNAL(MethodInfo("fired", PropertyInfo(Variant::INT, "value"), PropertyInfo(Variant::STRING, "text")));
}

} // namespace roomprobe_test
