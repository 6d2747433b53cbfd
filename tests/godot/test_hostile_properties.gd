extends RoomProbeTestCase
## Issue #38's sweep: every property of every class the extension registers, set to hostile
## values (NaN, infinities, huge and negative numbers, the hint range's ends and beyond, empty
## and missing paths, wrong resource types, invalid NodePaths), out of the tree and in it, with
## the node reparented and freed while it runs; then every method called with such arguments.
## Nothing may crash; a value the object does not keep as given is answered by an error or a
## warning naming the property; what is kept is finite and within the property's range; and
## every message logged names what it is about. The classes and properties come from ClassDB,
## so a new property is swept without a change here.

var _objects: Array[Object] = []
var _seen := 0


func _init() -> void:
	timeout_s = 240.0


func after_each() -> void:
	for o in _objects:
		if o is Node and is_instance_valid(o):
			o.free()
	_objects.clear()


## The classes the extension registers that a user can make.
static func extension_classes() -> Array[String]:
	var out: Array[String] = []
	for c in ClassDB.get_class_list():
		# BindingTestNode: the binding's own test fixture, not a user's class.
		if ClassDB.class_get_api_type(c) == ClassDB.API_EXTENSION and ClassDB.can_instantiate(c) and not c.begins_with("BindingTest"):
			out.append(c)
	out.sort()
	return out


## The properties a user can set: shown in the inspector or stored in scenes, not groups.
static func user_properties(p_class: String) -> Array[Dictionary]:
	var out: Array[Dictionary] = []
	for p in ClassDB.class_get_property_list(p_class, true):
		var usage: int = p.usage
		if usage & (PROPERTY_USAGE_GROUP | PROPERTY_USAGE_SUBGROUP | PROPERTY_USAGE_CATEGORY):
			continue
		if usage & (PROPERTY_USAGE_EDITOR | PROPERTY_USAGE_STORAGE):
			out.append(p)
	return out


## [low, high] of a PROPERTY_HINT_RANGE, with or_greater / or_less opening an end; null otherwise.
static func hint_range(p: Dictionary) -> Variant:
	if p.hint != PROPERTY_HINT_RANGE:
		return null
	var parts := String(p.hint_string).split(",")
	if parts.size() < 2:
		return null
	var low := float(parts[0])
	var high := float(parts[1])
	if parts.has("or_less"):
		low = -INF
	if parts.has("or_greater"):
		high = INF
	return [low, high]


## Hostile values of a property's type.
static func hostile_values(p: Dictionary) -> Array:
	var r = hint_range(p)
	match int(p.type):
		TYPE_FLOAT:
			var v: Array = [NAN, INF, -INF, -1e300, 1e300, -1.0, 0.0, 1e-300]
			if r != null:
				for end in r:
					if is_finite(end):
						v.append_array([end, end - 1e-3 * max(1.0, absf(end)), end + 1e-3 * max(1.0, absf(end))])
			return v
		TYPE_INT:
			var v: Array = [-1, 0, -(1 << 62), (1 << 62), 2147483648, -2147483649]
			if r != null:
				for end in r:
					if is_finite(end):
						v.append_array([int(end), int(end) - 1, int(end) + 1])
			return v
		TYPE_BOOL:
			return [true, false]
		TYPE_STRING:
			return ["", " ", "/nonexistent/dir/file.yaml", "res://no/such/file.yaml", "user://../../../../etc/passwd", "x".repeat(5000)]
		TYPE_NODE_PATH:
			return [NodePath(""), NodePath("/root/NoSuchNode"), NodePath("../../../.."), NodePath("..:position")]
		TYPE_VECTOR3:
			return [Vector3(NAN, 0, 0), Vector3(INF, -INF, 0), Vector3(1e300, 1e300, 1e300), Vector3.ZERO]
		TYPE_VECTOR2:
			return [Vector2(NAN, 0), Vector2(INF, -INF), Vector2(-1, -1)]
		TYPE_VECTOR2I, TYPE_VECTOR3I:
			return [Vector2i(-1, -1), Vector2i(1 << 30, 1 << 30)] if int(p.type) == TYPE_VECTOR2I else [Vector3i(-1, -1, -1), Vector3i(1 << 30, 0, 0)]
		TYPE_COLOR:
			return [Color(NAN, 0, 0), Color(INF, INF, INF, INF), Color(-1, -1, -1, -1)]
		TYPE_TRANSFORM3D:
			return [Transform3D(Basis(), Vector3(NAN, 0, 0)), Transform3D(Basis.from_scale(Vector3.ZERO), Vector3.ZERO)]
		TYPE_OBJECT:
			# null, and resources of a type the property does not name.
			return [null, Gradient.new(), StandardMaterial3D.new(), ImageTexture.new()]
		TYPE_ARRAY:
			return [[], [null, "x", NAN, -1]]
		TYPE_PACKED_FLOAT32_ARRAY, TYPE_PACKED_FLOAT64_ARRAY:
			return [PackedFloat64Array(), PackedFloat64Array([NAN, INF, -1e300])]
		TYPE_PACKED_VECTOR2_ARRAY:
			return [PackedVector2Array(), PackedVector2Array([Vector2(NAN, 0), Vector2(INF, 1)]), PackedVector2Array([Vector2.ZERO, Vector2.ZERO, Vector2.ZERO])]
		TYPE_PACKED_VECTOR3_ARRAY:
			return [PackedVector3Array(), PackedVector3Array([Vector3(NAN, 0, 0)])]
		TYPE_DICTIONARY:
			return [{}, {"x": NAN, 1: null}]
	return []


## Whether a kept value is finite in every component.
static func finite(v: Variant) -> bool:
	match typeof(v):
		TYPE_FLOAT:
			return is_finite(v)
		TYPE_VECTOR2, TYPE_VECTOR3, TYPE_COLOR:
			return v == v and not (str(v).contains("inf") or str(v).contains("nan"))
		TYPE_TRANSFORM3D:
			return v.is_finite()
	return true


static func same(a: Variant, b: Variant) -> bool:
	if typeof(a) == TYPE_FLOAT and typeof(b) == TYPE_FLOAT and is_nan(a) and is_nan(b):
		return true
	if typeof(a) != typeof(b) and not (typeof(a) in [TYPE_INT, TYPE_FLOAT] and typeof(b) in [TYPE_INT, TYPE_FLOAT]):
		return false
	return a == b


## Sets one property to one value and judges what came of it. p_what names the step in failures.
func _set_and_judge(p_object: Object, p_class: String, p: Dictionary, p_value: Variant) -> void:
	var name: String = p.name
	var what := "%s.%s = %s" % [p_class, name, str(p_value).left(60)]
	p_object.set(name, p_value)
	var kept = p_object.get(name)
	var logged := take_logged()
	var messages: Array = logged.errors + logged.warnings.filter(func(w: String) -> bool: return w.contains(p_class) or w.contains(name))
	_seen += 1
	for m in logged.errors:
		assert_true(m.contains(name), "%s: the error names the property: %s" % [what, m])
	assert_true(finite(kept), "%s: kept a finite value, got %s" % [what, kept])
	var r = hint_range(p)
	if r != null and typeof(kept) in [TYPE_INT, TYPE_FLOAT]:
		assert_true(kept >= r[0] and kept <= r[1], "%s: kept %s within the hint range [%s, %s]" % [what, kept, r[0], r[1]])
	if not same(kept, p_value) and typeof(p_value) != TYPE_OBJECT:
		assert_true(messages.size() > 0, "%s: kept %s instead, and said nothing naming %s" % [what, str(kept).left(60), name])


func _sweep_properties(p_object: Object, p_class: String) -> void:
	for p in user_properties(p_class):
		var original = p_object.get(p.name)
		for v in hostile_values(p):
			_set_and_judge(p_object, p_class, p, v)
		p_object.set(p.name, original)
		take_logged()


func test_every_property_out_of_the_tree() -> void:
	var classes := extension_classes()
	assert_true(classes.size() >= 6, "the extension's classes are found: %s" % [classes])
	for c in classes:
		var o = ClassDB.instantiate(c)
		_objects.append(o)
		_sweep_properties(o, c)
	assert_true(_seen > 200, "%d property values set" % _seen)


func test_every_node_property_in_the_tree_then_reparented_and_freed() -> void:
	var holder := Node3D.new()
	tree.root.add_child(holder)
	_objects.append(holder)
	for c in extension_classes():
		if not ClassDB.is_parent_class(c, "Node"):
			continue
		var n: Node = ClassDB.instantiate(c)
		holder.add_child(n)
		_sweep_properties(n, c)
		await tree.process_frame
		# Reparented and freed mid-run, with the hostile values' aftermath still queued.
		var other := Node3D.new()
		holder.add_child(other)
		n.reparent(other)
		await tree.process_frame
		other.free()
		await tree.process_frame
		take_logged()
	assert_true(_seen > 100, "%d property values set in the tree" % _seen)


## Arguments of a method's parameter types: the first hostile value of each, then the second.
static func hostile_arguments(p_args: Array, p_round: int) -> Array:
	var out := []
	for a in p_args:
		var values := hostile_values({"type": a.type, "hint": PROPERTY_HINT_NONE, "hint_string": ""})
		if a.type == TYPE_STRING:
			values = ["", "/nonexistent/dir/file.yaml"]  # never a path that could be written
		out.append(values[min(p_round, values.size() - 1)] if not values.is_empty() else null)
	return out


## Whether a message names one of the class's properties (what the call was missing, say).
static func names_a_property(p_message: String, p_class: String) -> bool:
	for p in user_properties(p_class):
		if p_message.contains(p.name):
			return true
	return false


func test_every_method_with_hostile_arguments() -> void:
	var calls := 0
	for c in extension_classes():
		var setters := {}
		for p in user_properties(c):
			setters[ClassDB.class_get_property_setter(c, p.name)] = true
			setters[ClassDB.class_get_property_getter(c, p.name)] = true
		for m in ClassDB.class_get_method_list(c, true):
			var name: String = m.name
			if name.begins_with("_") or setters.has(name) or m.flags & METHOD_FLAG_VIRTUAL:
				continue
			for round in 2:
				var o = ClassDB.instantiate(c)
				_objects.append(o)
				o.callv(name, hostile_arguments(m.args, round))
				calls += 1
				for e in take_logged().errors:
					assert_true(e.contains(c) or e.contains(name) or e.contains("/nonexistent/dir/file.yaml") or names_a_property(e, c),
							"%s.%s(%s): the error says what it is about: %s" % [c, name, hostile_arguments(m.args, round), e])
	assert_true(calls > 20, "%d calls" % calls)
