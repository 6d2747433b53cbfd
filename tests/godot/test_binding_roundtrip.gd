extends RoomProbeTestCase
## RoomProbe's own GDExtension binding, exercised from GDScript through the test-only
## extension in tests/binding/: every argument and return type, by ptrcall (typed calls)
## and by varcall (Object.call), both directions.

var _node  # BindingTestNode; untyped so that this file parses even if the class is missing.


func before_each() -> void:
	if not ClassDB.class_exists("BindingTestNode"):
		fail("BindingTestNode is not registered: the test extension did not load")
		return
	_node = ClassDB.instantiate("BindingTestNode")


func after_each() -> void:
	if is_instance_valid(_node):
		_node.free()
	_node = null


# One value per type the binding must carry. Floats are exact in single precision.
func _samples() -> Dictionary:
	var basis := Basis(Vector3(1, 2, 3), Vector3(4, 5, 6), Vector3(7, 8, 9.5))
	return {
		"echo_bool": true,
		"echo_int": -(1 << 40) - 3,
		"echo_int32": -123456,
		"echo_uint8": 200,
		"echo_float": 1.0 / 3.0,
		"echo_float32": 0.25,
		"echo_string": "Ünïcødé room 🌍",
		"echo_string_name": &"probe_name",
		"echo_node_path": NodePath("A/B:c"),
		"echo_vector2": Vector2(1.5, -2.5),
		"echo_vector2i": Vector2i(-7, 9),
		"echo_rect2": Rect2(1, 2, 3, 4),
		"echo_rect2i": Rect2i(-1, -2, 30, 40),
		"echo_vector3": Vector3(0.5, -1.25, 8),
		"echo_vector3i": Vector3i(1, -2, 3),
		"echo_transform2d": Transform2D(Vector2(1, 2), Vector2(3, 4), Vector2(5, 6)),
		"echo_vector4": Vector4(1, 2, 3, 4.5),
		"echo_vector4i": Vector4i(1, 2, -3, 4),
		"echo_plane": Plane(Vector3(0, 1, 0), 2.5),
		"echo_quaternion": Quaternion(0.5, 0.5, 0.5, 0.5),
		"echo_aabb": AABB(Vector3(1, 2, 3), Vector3(4, 5, 6)),
		"echo_basis": basis,
		"echo_transform3d": Transform3D(basis, Vector3(10, 11, 12)),
		"echo_projection": Projection(Vector4(1, 2, 3, 4), Vector4(5, 6, 7, 8), Vector4(9, 10, 11, 12), Vector4(13, 14, 15, 16)),
		"echo_color": Color(0.25, 0.5, 0.75, 1.0),
		"echo_rid": RenderingServer.get_white_texture() if false else RID(),
		"echo_callable": Callable(self, "_samples"),
		"echo_signal": Signal(_node, "fired"),
		"echo_dictionary": {"a": 1, 2: [3, 4], "nested": {"x": Vector3.ONE}},
		"echo_array": [1, "two", 3.0, null, Vector2i(4, 5)],
		"echo_packed_byte_array": PackedByteArray([0, 1, 254, 255]),
		"echo_packed_int32_array": PackedInt32Array([-2147483648, 0, 2147483647]),
		"echo_packed_int64_array": PackedInt64Array([-(1 << 62), 1 << 62]),
		"echo_packed_float32_array": PackedFloat32Array([0.5, -1.5]),
		"echo_packed_float64_array": PackedFloat64Array([1.0 / 3.0, 1e300]),
		"echo_packed_string_array": PackedStringArray(["a", "ß", ""]),
		"echo_packed_vector2_array": PackedVector2Array([Vector2(1, 2), Vector2(3, 4)]),
		"echo_packed_vector3_array": PackedVector3Array([Vector3(1, 2, 3)]),
		"echo_packed_color_array": PackedColorArray([Color.RED, Color(0, 0, 0, 0)]),
		"echo_packed_vector4_array": PackedVector4Array([Vector4(1, 2, 3, 4)]),
		"echo_variant": [Vector3(1, 2, 3), "x"],
		"echo_mode": 5,
	}


func test_every_type_round_trips_by_ptrcall_and_varcall() -> void:
	var samples := _samples()
	for method in samples:
		var value = samples[method]
		var typed = _node.call(method, value)  # varcall: through Variants
		assert_eq(typeof(typed), typeof(value), "%s keeps the type %s" % [method, type_string(typeof(value))])
		assert_eq(typed, value, "%s by varcall" % method)
	# Typed calls compile to ptrcalls where GDScript knows the types.
	var node: Node3D = _node
	assert_eq(_node.echo_int(-5), -5, "echo_int by direct call")
	assert_eq(_node.echo_vector3(Vector3(1, 2, 3)), Vector3(1, 2, 3), "echo_vector3 by direct call")
	assert_eq(_node.echo_string("héllo"), "héllo", "echo_string by direct call")
	assert_eq(_node.echo_packed_vector3_array(PackedVector3Array([Vector3.UP])), PackedVector3Array([Vector3.UP]))
	assert_eq(node.get_class(), "BindingTestNode", "the engine sees the extension class")


func test_integer_metadata_truncates_like_the_engine() -> void:
	# int32 and uint8 arguments are declared with metadata; values wrap as C++ casts do.
	assert_eq(_node.echo_uint8(255), 255)
	assert_eq(_node.echo_uint8(256), 0, "uint8 wraps")
	assert_eq(_node.echo_int32(1 << 31), -(1 << 31), "int32 wraps")


func test_objects_and_refs_round_trip() -> void:
	var child := Node.new()
	_node.add_child(child)
	assert_eq(_node.echo_node(child), child, "Node* round trip")
	assert_eq(_node.echo_node(null), null, "null Node*")
	assert_eq(_node.count_children_of(_node), 1, "C++ calls an engine method on a GDScript-made node")
	var res := Resource.new()
	assert_eq(_node.echo_resource(res), res, "Ref<Resource> round trip")
	assert_eq(_node.echo_resource(null), null, "null Ref")


func test_methods_with_work_in_cpp() -> void:
	var pts := PackedVector3Array([Vector3(1, 2, 3), Vector3(-1, 0, 0.5)])
	assert_eq(_node.scale_points(pts, 2.0), PackedVector3Array([Vector3(2, 4, 6), Vector3(-2, 0, 1)]))
	assert_eq(pts[0], Vector3(1, 2, 3), "the caller's array is not modified")
	assert_eq(_node.describe({"b": 2, "a": Vector2(1, 0)}), "a=(1.0, 0.0);b=2;")
	assert_eq(_node.call_on(self, "_double", 21), 42, "C++ calls a GDScript method through Object.call")


func _double(x):
	return x * 2


func test_default_arguments_and_static_methods() -> void:
	assert_eq(_node.sum_with_defaults(1), 1 + 7 + 3, "both defaults")
	assert_eq(_node.sum_with_defaults(1, 2), 1 + 2 + 3, "one default")
	assert_eq(_node.sum_with_defaults(1, 2, "xyzzy"), 1 + 2 + 5, "no default")
	assert_eq(ClassDB.class_call_static("BindingTestNode", "add_static", 40, 2), 42, "static method")


func test_properties_with_hints_and_groups() -> void:
	var props := {}
	var order: Array[String] = []
	for p in ClassDB.class_get_property_list("BindingTestNode", true):
		props[p.name] = p
		order.append(p.name)
	assert_eq(props["speed"].type, TYPE_FLOAT)
	assert_eq(props["speed"].hint, PROPERTY_HINT_RANGE)
	assert_eq(props["speed"].hint_string, "0,10,0.5,suffix:m/s")
	assert_eq(props["mode"].hint, PROPERTY_HINT_ENUM)
	assert_eq(props["mode"].hint_string, "Off:0,On:5")
	assert_eq(props["config_file"].hint, PROPERTY_HINT_FILE)
	assert_eq(props["resource"].hint, PROPERTY_HINT_RESOURCE_TYPE)
	assert_eq(props["resource"].hint_string, "Resource")
	assert_true(props.has("Motion") and props["Motion"].usage & PROPERTY_USAGE_GROUP, "group Motion")
	assert_true(props.has("Files") and props["Files"].usage & PROPERTY_USAGE_SUBGROUP, "subgroup Files")
	assert_true(order.find("Motion") < order.find("speed"), "the group precedes its members")
	assert_eq(_node.speed, 1.5, "default value")
	_node.speed = 3.0
	assert_eq(_node.get_speed(), 3.0, "setter and getter")
	_node.set("mode", 5)
	assert_eq(_node.mode, 5)


func test_constants_and_enums() -> void:
	assert_eq(ClassDB.class_get_integer_constant("BindingTestNode", "ANSWER"), 42)
	assert_eq(ClassDB.class_get_integer_constant("BindingTestNode", "MODE_ON"), 5)
	assert_true(ClassDB.class_has_enum("BindingTestNode", "Mode"), "enum Mode")
	assert_eq(ClassDB.class_get_enum_constants("BindingTestNode", "Mode"), PackedStringArray(["MODE_OFF", "MODE_ON"]))
	var args: Array = []
	for m in ClassDB.class_get_method_list("BindingTestNode", true):
		if m.name == "echo_mode":
			args = m.args
	assert_eq(args.size(), 1, "echo_mode is listed")
	if args.size() == 1:
		assert_eq(args[0].class_name, &"BindingTestNode.Mode", "enum argument carries its enum name")


func test_signals() -> void:
	var got: Array = []
	var signals := ClassDB.class_get_signal_list("BindingTestNode", true)
	assert_eq(signals.size(), 1)
	assert_eq(signals[0].name, "fired")
	assert_eq(signals[0].args.size(), 2)
	_node.fired.connect(func(v, t): got.append([v, t]))
	_node.fire(7, "seven")
	assert_eq(got, [[7, "seven"]], "emitted from C++, received in GDScript")


func test_virtual_overrides_are_called() -> void:
	add_to_tree(_node)
	await wait_frames(3)
	var calls: Dictionary = _node.get_virtual_calls()
	assert_eq(calls.enter_tree, 1, "_enter_tree")
	assert_eq(calls.ready, 1, "_ready")
	assert_eq(calls.notification_ready, 1, "_notification(NOTIFICATION_READY)")
	assert_true(calls.process >= 2, "_process ran each frame (%d)" % calls.process)
	assert_true(calls.last_delta > 0.0, "_process gets a delta")
	assert_true(calls.physics_process >= 1, "_physics_process ran (%d)" % calls.physics_process)
	_node.get_parent().remove_child(_node)
	assert_eq(_node.get_virtual_calls().exit_tree, 1, "_exit_tree")


func test_objects_are_freed() -> void:
	var before_nodes: int = ClassDB.class_call_static("BindingTestNode", "live_count")
	var n = ClassDB.instantiate("BindingTestNode")
	assert_eq(ClassDB.class_call_static("BindingTestNode", "live_count"), before_nodes + 1)
	n.free()
	assert_eq(ClassDB.class_call_static("BindingTestNode", "live_count"), before_nodes, "free() deletes the C++ instance")
	var before_refs: int = ClassDB.class_call_static("BindingTestRef", "live_count")
	var r = _node.make_ref(9)
	assert_eq(r.value, 9, "Ref made in C++ reaches GDScript")
	assert_eq(r.get_reference_count(), 1, "GDScript holds the only reference")
	assert_eq(ClassDB.class_call_static("BindingTestRef", "live_count"), before_refs + 1)
	r = null
	assert_eq(ClassDB.class_call_static("BindingTestRef", "live_count"), before_refs, "dropping the last Ref frees it")
	var img: Image = _node.make_image(4, 3)
	assert_eq(img.get_size(), Vector2i(4, 3), "engine Ref<Image> from a static engine method")
	assert_eq(img.get_pixel(2, 1), Color(1, 0, 0, 1))
	assert_eq(img.get_reference_count(), 1, "no reference leaked in C++")
