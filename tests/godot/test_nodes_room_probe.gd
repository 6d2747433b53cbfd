extends RoomProbeTestCase
## RoomProbe through Godot: a box room whose charts are painted in distinct flat colours (the
## atlas put in with CoarseRoomModel.set_atlas_image) is rendered into a Cubemap at the room's
## centre. Each face's centre pixel must show the surface that lies in that face's direction
## (layer order +X -X +Y -Y +Z -Z), and the SH's DC term must be the solid-angle mean colour.

# A 4 m x 3 m box, 2.5 m high. Floorplan points (x, y) are world (x, z).
const PLAN := [Vector2(0, 0), Vector2(4, 0), Vector2(4, 3), Vector2(0, 3)]
const HEIGHT := 2.5
const CENTRE := Vector3(2.0, 1.25, 1.5)
const RES := 32
const FLOOR_COLOR := Color(0.8, 0.5, 0.1)
const CEILING_COLOR := Color(0.2, 0.9, 0.6)
const WALL_COLORS := [Color(0.9, 0.1, 0.1), Color(0.1, 0.7, 0.2), Color(0.1, 0.2, 0.9), Color(0.6, 0.6, 0.1)]
# Layer i looks along FACE_DIRS[i].
const FACE_DIRS := [Vector3.RIGHT, Vector3.LEFT, Vector3.UP, Vector3.DOWN, Vector3.BACK, Vector3.FORWARD]

var _root: Node3D
var _room  # CoarseRoomModel
var _probe  # RoomProbe


func before_each() -> void:
	_root = Node3D.new()
	_room = ClassDB.instantiate("CoarseRoomModel")
	_room.floorplan = PackedVector2Array(PLAN)
	_room.ceiling_height = HEIGHT
	_room.texel_size = 0.05
	_room.name = "Room"
	_root.add_child(_room)
	_probe = ClassDB.instantiate("RoomProbe")
	_probe.resolution = RES
	_probe.position = CENTRE
	_root.add_child(_probe)
	_probe.coarse_model = NodePath("../Room")


func after_each() -> void:
	if is_instance_valid(_root):
		_root.free()
	_root = null
	_room = null
	_probe = null


## Paints every chart in its colour; returns, per chart, its colour and inward normal.
func _paint_atlas() -> Array:
	var size: Vector2i = _room.get_atlas_size()
	var img := Image.create_empty(size.x, size.y, false, Image.FORMAT_RGBF)
	img.fill(Color(0, 0, 0))
	var out := []
	for c in _room.get_charts():
		var color: Color
		match c.kind:
			"floor":
				color = FLOOR_COLOR
			"ceiling":
				color = CEILING_COLOR
			_:
				color = WALL_COLORS[c.wall_index]
		img.fill_rect(c.rect, color)
		out.append({"color": color, "normal": c.normal, "kind": c.kind})
	assert_true(_room.set_atlas_image(img), "set_atlas_image accepts an atlas-sized image")
	return out


func _solid_angle(u: int, v: int, n: int) -> float:
	var f := func(x: float, y: float) -> float: return atan2(x * y, sqrt(x * x + y * y + 1.0))
	var x0 := 2.0 * u / n - 1.0
	var x1 := 2.0 * (u + 1) / n - 1.0
	var y0 := 2.0 * v / n - 1.0
	var y1 := 2.0 * (v + 1) / n - 1.0
	return f.call(x0, y0) - f.call(x0, y1) - f.call(x1, y0) + f.call(x1, y1)


func test_charts_describe_the_box() -> void:
	var charts: Array = _room.get_charts()
	assert_eq(charts.size(), PLAN.size() + 2, "four walls, floor, ceiling")
	var kinds := {}
	for c in charts:
		kinds[c.kind] = kinds.get(c.kind, 0) + 1
		var r: Rect2i = c.rect
		assert_true(r.size.x > 0 and r.size.y > 0, "chart rect %s" % r)
	assert_eq(kinds, {"wall": 4, "floor": 1, "ceiling": 1})
	assert_false(_room.has_texture_data(), "no texture before set_atlas_image")
	_paint_atlas()
	assert_true(_room.has_texture_data())
	assert_eq(_room.get_atlas_image().get_size(), _room.get_atlas_size())


func test_wrong_atlas_size_is_rejected() -> void:
	expect_error("atlas's size")
	assert_false(_room.set_atlas_image(Image.create_empty(4, 4, false, Image.FORMAT_RGB8)))
	assert_false(_room.has_texture_data())


func test_cubemap_faces_show_the_surfaces_in_their_directions() -> void:
	var charts := _paint_atlas()
	add_to_tree(_root)
	var updates := [0]
	_probe.environment_map_updated.connect(func(): updates[0] += 1)
	assert_true(_probe.update_now(), "update_now")
	assert_eq(updates[0], 1, "environment_map_updated emitted once")
	var cube: Cubemap = _probe.get_cubemap()
	if not assert_not_null(cube, "a Cubemap"):
		return
	assert_eq(cube.get_layers(), 6)
	assert_eq(Vector2i(cube.get_width(), cube.get_height()), Vector2i(RES, RES))
	for layer in 6:
		var face: Image = _probe.get_face_image(layer)
		assert_eq(face.get_size(), Vector2i(RES, RES), "face %d size" % layer)
		# The surface seen along this face's axis: the one whose inward normal points back.
		var expected := Color(-1, -1, -1)
		for c in charts:
			if (c.normal as Vector3).dot(-FACE_DIRS[layer]) > 0.99:
				expected = c.color
		var got := face.get_pixel(RES / 2, RES / 2)
		assert_near(got, expected, 1e-4, "layer %d (looking along %s) centre pixel" % [layer, FACE_DIRS[layer]])
	# Spot checks with names, against the classic wrong-convention bugs.
	assert_near(_probe.get_face_image(2).get_pixel(RES / 2, RES / 2), CEILING_COLOR, 1e-4, "+Y shows the ceiling")
	assert_near(_probe.get_face_image(3).get_pixel(RES / 2, RES / 2), FLOOR_COLOR, 1e-4, "-Y shows the floor")
	# The net (the inspector's preview, save_png_net's image): +Y in the top row's second cell,
	# -Y below it, each face clamped and sRGB-encoded.
	var net: Image = _probe.get_net_image()
	if assert_not_null(net, "a net image"):
		assert_eq(net.get_size(), Vector2i(4 * RES, 3 * RES), "4N x 3N")
		assert_near(net.get_pixel(RES + RES / 2, RES / 2), CEILING_COLOR.linear_to_srgb(), 1.5 / 255.0, "+Y on top")
		assert_near(net.get_pixel(RES + RES / 2, 2 * RES + RES / 2), FLOOR_COLOR.linear_to_srgb(), 1.5 / 255.0, "-Y below")
	# Updating again with the same size updates the same Cubemap in place.
	assert_true(_probe.update_now())
	assert_eq(_probe.get_cubemap(), cube, "same Cubemap resource, updated in place")


func test_sh_dc_term_is_mean_colour_times_sqrt_4pi() -> void:
	_paint_atlas()
	add_to_tree(_root)
	assert_true(_probe.update_now())
	var sh: PackedVector3Array = _probe.get_sh_coefficients()
	assert_eq(sh.size(), 25)
	# Solid-angle weighted mean over the six faces: c0 = y00 * integral L dOmega
	# = (1 / (2 sqrt(pi))) * 4 pi * mean = sqrt(4 pi) * mean. Floats: 1e-4 relative is ample.
	var total := Vector3()
	var omega := 0.0
	for layer in 6:
		var face: Image = _probe.get_face_image(layer)
		for v in RES:
			for u in RES:
				var w := _solid_angle(u, v, RES)
				var c := face.get_pixel(u, v)
				total += Vector3(c.r, c.g, c.b) * w
				omega += w
	assert_near(omega, 4.0 * PI, 1e-4, "texel solid angles sum to 4 pi")
	var mean := total / omega
	assert_near(sh[0], mean * sqrt(4.0 * PI), 1e-4 * sqrt(4.0 * PI), "SH DC term")
	# Independent of the pixels: the mean lies between the darkest and brightest surface colour.
	assert_true(mean.x > 0.1 and mean.x < 0.9, "mean red %f" % mean.x)


func test_target_material_receives_cubemap_and_sh() -> void:
	_paint_atlas()
	var mat := ShaderMaterial.new()
	mat.shader = load("res://addons/roomprobe/shaders/mirror.gdshader")
	_probe.target_material = mat
	add_to_tree(_root)  # ready renders once (UPDATE_ONCE)
	assert_eq(mat.get_shader_parameter("environment"), _probe.get_cubemap(), "environment uniform is the cubemap")
	var sh = mat.get_shader_parameter("sh")
	assert_eq(sh.size() if sh != null else 0, 25, "sh uniform holds 25 coefficients")
	# A material that cannot read the map is named and refused; the good one stays (issue #38:
	# a StandardMaterial3D became null without a word).
	expect_error("RoomProbe.target_material: a StandardMaterial3D cannot read the map")
	_probe.target_material = StandardMaterial3D.new()
	assert_eq(_probe.target_material, mat)


## The editor saves the scene with the user's own values: before saving
## (NOTIFICATION_EDITOR_PRE_SAVE) the probe puts back everything it set on the user's material,
## ReflectionProbe and Environment, so no cubemap, sky or probe placement is written into the
## .tscn; after saving it drives them again. Leaving the tree puts them back too.
func test_the_saved_scene_keeps_the_users_values() -> void:
	_paint_atlas()
	var mat := ShaderMaterial.new()
	mat.shader = load("res://addons/roomprobe/shaders/mirror.gdshader")
	_probe.target_material = mat
	var reflection := ReflectionProbe.new()
	reflection.name = "Reflection"
	reflection.size = Vector3(1, 2, 3)
	reflection.cull_mask = 5
	reflection.position = Vector3(0.5, 0.5, 0.5)
	_root.add_child(reflection)
	reflection.owner = _root
	var world := WorldEnvironment.new()
	world.name = "World"
	var env := Environment.new()
	env.reflected_light_source = Environment.REFLECTION_SOURCE_BG
	world.environment = env
	_root.add_child(world)
	world.owner = _root
	for n in [_room, _probe]:
		n.owner = _root
	add_to_tree(_root)
	_probe.reflection_probe = NodePath("../Reflection")
	_probe.world_environment = NodePath("../World")
	assert_true(_probe.update_now())
	assert_eq(mat.get_shader_parameter("environment"), _probe.get_cubemap(), "driven: the material")
	assert_ne(reflection.size, Vector3(1, 2, 3), "driven: the ReflectionProbe's box")
	assert_not_null(env.sky, "driven: the sky")
	_probe.notification(Node.NOTIFICATION_EDITOR_PRE_SAVE)
	assert_null(mat.get_shader_parameter("environment"), "saved without the cubemap")
	assert_null(mat.get_shader_parameter("sh"))
	assert_eq(reflection.size, Vector3(1, 2, 3), "saved with the user's box")
	assert_eq(reflection.cull_mask, 5)
	assert_eq(reflection.position, Vector3(0.5, 0.5, 0.5))
	assert_false(reflection.box_projection)
	assert_null(env.sky, "saved without the probe's sky")
	assert_eq(env.reflected_light_source, Environment.REFLECTION_SOURCE_BG)
	var packed := PackedScene.new()
	assert_eq(packed.pack(_root), OK)
	var path := "user://roomprobe_saved_scene_test.tscn"
	assert_eq(ResourceSaver.save(packed, path), OK)
	var text := FileAccess.get_file_as_string(path)
	DirAccess.remove_absolute(ProjectSettings.globalize_path(path))
	assert_false(text.contains("Image"), "no image in the saved scene")
	assert_false(text.contains("Sky"), "no sky in the saved scene")
	assert_true(text.length() < 20000, "the saved scene is small: %d bytes" % text.length())
	_probe.notification(Node.NOTIFICATION_EDITOR_POST_SAVE)
	assert_eq(mat.get_shader_parameter("environment"), _probe.get_cubemap(), "driven again after saving")
	assert_not_null(env.sky)
	assert_ne(reflection.size, Vector3(1, 2, 3))
	_root.remove_child(_probe)
	assert_null(env.sky, "a probe that leaves puts the sky back")
	assert_eq(reflection.size, Vector3(1, 2, 3))
	_root.add_child(_probe)


func test_update_always_renders_every_frame() -> void:
	_paint_atlas()
	_probe.update_mode = 1  # UPDATE_ALWAYS
	var updates := [0]
	_probe.environment_map_updated.connect(func(): updates[0] += 1)
	add_to_tree(_root)
	await wait_frames(3)
	assert_true(updates[0] >= 3, "updated on ready and each frame: %d" % updates[0])


## Issue #37: a probe in Once mode readied before its room exists (a recording's room comes after
## the scene starts) rendered never. Once means once per room: when the room comes, and again for
## the next room, and not in between.
func test_update_once_renders_once_per_room() -> void:
	_room.floorplan = PackedVector2Array()  # no room yet
	_probe.update_mode = 0  # UPDATE_ONCE
	var updates := [0]
	_probe.environment_map_updated.connect(func(): updates[0] += 1)
	add_to_tree(_root)
	await wait_frames(3)
	assert_eq(updates[0], 0, "no map without a room")
	_room.floorplan = PackedVector2Array(PLAN)
	await wait_frames(4)
	assert_eq(updates[0], 1, "one map once the room exists")
	assert_not_null(_probe.get_cubemap(), "the map is there")
	_room.floorplan = PackedVector2Array([Vector2(0, 0), Vector2(5, 0), Vector2(5, 3), Vector2(0, 3)])
	await wait_frames(4)
	assert_eq(updates[0], 2, "one more for the next room, none in between")


func test_warnings_say_what_is_missing() -> void:
	var lone = ClassDB.instantiate("RoomProbe")
	var text := " ".join(lone.get_warnings())
	assert_true(text.contains("coarse_model"), text)
	assert_true(text.contains("reaches nothing"), text)
	lone.free()
	_probe.coarse_model = NodePath("../Nowhere")
	add_to_tree(_root)
	text = " ".join(_probe.get_warnings())
	assert_true(text.contains("does not lead to a CoarseRoomModel"), text)
	expect_error("does not lead to a CoarseRoomModel")
	assert_false(_probe.update_now(), "no map without a model")
	assert_null(_probe.get_cubemap())
	assert_eq(_probe.get_sh_coefficients().size(), 0)


func test_a_probe_far_outside_the_room_says_so() -> void:
	_paint_atlas()
	add_to_tree(_root)
	assert_true(_probe.update_now())
	assert_false(" ".join(_probe.get_warnings()).contains("outside the room"), str(_probe.get_warnings()))
	# 20 m beyond the 4 m wall: its map sees the room from behind the walls (issue #17).
	_probe.position = Vector3(24.0, 1.25, 1.5)
	expect_warning("is 20.00 m outside the room")
	assert_true(_probe.update_now())
	assert_true(" ".join(_probe.get_warnings()).contains("20.00 m outside the room"), str(_probe.get_warnings()))
	# A little outside is a floorplan's slack, not a mistake; back inside, the warning goes.
	_probe.position = Vector3(4.3, 1.25, 1.5)
	assert_true(_probe.update_now())
	assert_false(" ".join(_probe.get_warnings()).contains("outside the room"), str(_probe.get_warnings()))
