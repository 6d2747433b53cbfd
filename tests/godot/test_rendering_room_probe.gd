extends RoomProbeTestCase
## A mirror sphere (shaders/mirror.gdshader) fed by a RoomProbe's Cubemap, rendered by Godot:
## checks that Godot samples the probe's Cubemap with the same direction convention as the
## core's cubemap_direction. Seen from above, the sphere's centre reflects straight up and must
## show the ceiling; seen from +Z it reflects towards +Z (the wall facing -Z); from +X, the
## wall facing -X. Also: distance-aware reflections against rays traced by hand, the other
## delivery routes and PRT. Runs only in the "rendering" suite.

const SIZE := Vector2i(96, 96)
const PLAN := [Vector2(0, 0), Vector2(4, 0), Vector2(4, 3), Vector2(0, 3)]
const HEIGHT := 2.5
const CENTRE := Vector3(2.0, 1.25, 1.5)
const FLOOR_COLOR := Color(0.8, 0.5, 0.1)
const CEILING_COLOR := Color(0.2, 0.9, 0.6)
const WALL_COLORS := [Color(0.9, 0.1, 0.1), Color(0.1, 0.7, 0.2), Color(0.1, 0.2, 0.9), Color(0.6, 0.6, 0.1)]
# The distance-aware test's mirror: 1.1 m from CENTRE, 0.3 m from the +X wall; the room as a box.
const SPHERE_CENTRE := Vector3(3.1, 1.25, 1.5)
const SPHERE_RADIUS := 0.6
const BOX_MAX := Vector3(4.0, HEIGHT, 3.0)
# Hits this near another face of the box are left out: the map's texels there blend two surfaces.
const EDGE_MARGIN_M := 0.1

# rough_metal against a StandardMaterial3D (sky route): the mean relative colour difference
# allowed. The sky route is not exact either: Godot renders the 64^2 map into its own 256^2
# radiance map and filters that with 32 GGX samples; the two agree in brightness within 3-8 % per
# channel but not in hue (Godot's is up to 10 % less blue at roughness 0.8), 0.12-0.17 in all.
# A roughness 0.3 off gives 0.36-0.58.
const ROUGH_METAL_TOLERANCE := 0.2

var _viewport: SubViewport
var _holder: Node3D


func after_each() -> void:
	for n in [_viewport, _holder]:
		if is_instance_valid(n):
			n.free()
	_viewport = null
	_holder = null


func test_mirror_sphere_reflects_the_right_surfaces() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	var by_normal := {}  # a surface's colour by the direction from which it is seen
	var material := ShaderMaterial.new()
	material.shader = load("res://addons/roomprobe/shaders/mirror.gdshader")
	var probe = _room_and_probe(material, by_normal)
	assert_not_null(probe.get_cubemap(), "the probe rendered on ready")

	# Camera position and rotation; the sphere's centre pixel reflects back towards the camera.
	var views: Array = [[Vector3(0, 3, 0), Vector3(-90, 0, 0), Vector3i(0, 1, 0), "from above: the ceiling"],
			[Vector3(0, 0, 3), Vector3(0, 0, 0), Vector3i(0, 0, 1), "from +Z: the wall seen towards +Z"],
			[Vector3(3, 0, 0), Vector3(0, 90, 0), Vector3i(1, 0, 0), "from +X: the wall seen towards +X"]]
	# One viewport (its own world: a sphere and a camera) per view, rendered together.
	_viewport = SubViewport.new()  # holds the others, so that after_each frees them all
	_viewport.size = Vector2i(4, 4)
	var shots: Array[SubViewport] = []
	for view in views:
		var vp := _make_view(material, view[0], view[1])
		_viewport.add_child(vp)
		shots.append(vp)
	# The other two shaders compile and show the room too (fed by hand: one target_material).
	var others: Array[SubViewport] = []
	for path in ["res://addons/roomprobe/shaders/rough_metal.gdshader", "res://addons/roomprobe/shaders/glass.gdshader", "res://addons/roomprobe/shaders/sh_diffuse.gdshader"]:
		var m := ShaderMaterial.new()
		m.shader = load(path)
		m.set_shader_parameter("environment", probe.get_cubemap())
		m.set_shader_parameter("sh", probe.get_sh_coefficients())
		if path.contains("rough"):
			m.set_shader_parameter("roughness", 0.9)  # a coarse level of the GGX chain
		var vp := _make_view(m, Vector3(0, 3, 0), Vector3(-90, 0, 0))
		_viewport.add_child(vp)
		others.append(vp)
	add_to_tree(_viewport)
	await wait_frames(4)
	for vp in others:
		var img := vp.get_texture().get_image()
		if not artifacts_dir.is_empty():
			img.save_png(artifacts_dir.path_join("room_probe_other_%d.png" % others.find(vp)))
		var c := img.get_pixel(SIZE.x / 2, SIZE.y / 2).srgb_to_linear()
		assert_true(c.get_luminance() > 0.05, "shader %d shows the room, not black: %s" % [others.find(vp), c])
	for i in views.size():
		var view: Array = views[i]
		var img := shots[i].get_texture().get_image()
		if not assert_not_null(img, "viewport image"):
			return
		if not artifacts_dir.is_empty():
			DirAccess.make_dir_recursive_absolute(artifacts_dir)
			img.save_png(artifacts_dir.path_join("room_probe_%s.png" % str(view[2])))
		var got := img.get_pixel(SIZE.x / 2, SIZE.y / 2).srgb_to_linear()
		# The nearest of the six surface colours must be the expected one.
		var best := Color()
		var best_d := INF
		for k in by_normal:
			var c: Color = by_normal[k]
			var d := Vector3(c.r - got.r, c.g - got.g, c.b - got.b).length()
			if d < best_d:
				best_d = d
				best = c
		assert_eq(best, by_normal[view[2]], "%s (pixel %s)" % [view[3], got])
		assert_true(best_d < 0.1, "%s: pixel %s is close to %s" % [view[3], got, best])


## Distance-aware reflections (mirror.gdshader's distance_aware, parallax.gdshaderinc): a mirror
## sphere 1.1 m from the probe, 0.3 m from a wall of the coloured room. For each sphere pixel the
## test traces the reflected ray itself: from the sphere's surface to the room's box (what
## distance-aware reflection must show) and from the probe along the same direction (what the
## plain lookup shows). Where the two surfaces differ, the distance-aware image must show the
## first and the plain one the second. The probe sets probe_position itself (position_parameter).
func test_distance_aware_mirror_shows_where_the_reflected_ray_meets_the_room() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	var by_normal := {}
	var shader: Shader = load("res://addons/roomprobe/shaders/mirror.gdshader")
	var aware := ShaderMaterial.new()
	aware.shader = shader
	aware.set_shader_parameter("distance_aware", true)
	var probe = _room_and_probe(aware, by_normal)
	if not assert_not_null(probe.get_cubemap(), "the probe rendered on ready"):
		return
	assert_near(aware.get_shader_parameter("probe_position"), CENTRE, 1e-4, "the probe gives its position to the material")
	var plain := ShaderMaterial.new()
	plain.shader = shader
	plain.set_shader_parameter("environment", probe.get_cubemap())
	plain.set_shader_parameter("probe_position", CENTRE)

	_viewport = SubViewport.new()
	_viewport.size = Vector2i(4, 4)
	var shots: Array[SubViewport] = []
	for m in [aware, plain]:
		shots.append(_make_view(m, SPHERE_CENTRE + Vector3(0, 0, 2.2), Vector3.ZERO, SPHERE_CENTRE, SPHERE_RADIUS))
	for vp in shots:
		_viewport.add_child(vp)
	add_to_tree(_viewport)
	await wait_frames(4)
	var images: Array[Image] = []
	for i in shots.size():
		var img := shots[i].get_texture().get_image()
		if not assert_not_null(img, "viewport image"):
			return
		if not artifacts_dir.is_empty():
			DirAccess.make_dir_recursive_absolute(artifacts_dir)
			img.save_png(artifacts_dir.path_join("parallax_%s.png" % ["distance_aware", "plain"][i]))
		images.append(img)

	var cam: Camera3D = shots[0].get_child(2)
	var sphere_pixels := 0
	var differing := 0
	var aware_right := 0
	var aware_right_differing := 0
	var plain_right_differing := 0
	for y in SIZE.y:
		for x in SIZE.x:
			var origin := cam.project_ray_origin(Vector2(x + 0.5, y + 0.5))
			var ray := cam.project_ray_normal(Vector2(x + 0.5, y + 0.5))
			var to_centre := origin - SPHERE_CENTRE
			var b := to_centre.dot(ray)
			var disc := b * b - (to_centre.length_squared() - SPHERE_RADIUS * SPHERE_RADIUS)
			if disc <= 0.0:
				continue
			var point := origin + (-b - sqrt(disc)) * ray
			var normal := (point - SPHERE_CENTRE).normalized()
			if absf(normal.dot(ray)) < 0.3:
				continue  # the rim: a pixel there covers a wide fan of reflections
			var reflected := ray - 2.0 * ray.dot(normal) * normal
			var expected = _box_surface(point, reflected)
			var along = _box_surface(CENTRE, reflected)
			if expected == null or along == null:
				continue
			sphere_pixels += 1
			var got_aware: Color = _nearest_surface(by_normal, images[0].get_pixel(x, y).srgb_to_linear())[0]
			var got_plain: Color = _nearest_surface(by_normal, images[1].get_pixel(x, y).srgb_to_linear())[0]
			if got_aware == by_normal[expected]:
				aware_right += 1
			if expected != along:
				differing += 1
				if got_aware == by_normal[expected]:
					aware_right_differing += 1
				if got_plain == by_normal[along]:
					plain_right_differing += 1
	assert_true(sphere_pixels > 1000, "the sphere covers the image: %d pixels" % sphere_pixels)
	assert_true(differing > 150, "parallax matters on this sphere: %d pixels see another surface than along the ray from the probe" % differing)
	assert_true(aware_right >= 0.95 * sphere_pixels, "distance-aware: %d of %d pixels show the surface the reflected ray meets" % [aware_right, sphere_pixels])
	assert_true(aware_right_differing >= 0.9 * differing,
			"distance-aware, where parallax matters: %d of %d pixels right" % [aware_right_differing, differing])
	assert_true(plain_right_differing >= 0.9 * differing,
			"plain lookup, where parallax matters: %d of %d pixels show the surface along the ray from the probe" % [plain_right_differing, differing])


## The surface of the room's box that the ray from p_origin (inside) along p_dir meets, as the
## key of by_normal (the direction it is seen from); null when the hit is near an edge.
func _box_surface(p_origin: Vector3, p_dir: Vector3) -> Variant:
	var best_t := INF
	var key := Vector3i()
	for axis in 3:
		if absf(p_dir[axis]) < 1e-9:
			continue
		var bound: float = BOX_MAX[axis] if p_dir[axis] > 0.0 else 0.0
		var t := (bound - p_origin[axis]) / p_dir[axis]
		if t > 0.0 and t < best_t:
			best_t = t
			key = Vector3i()
			key[axis] = 1 if p_dir[axis] > 0.0 else -1
	var hit := p_origin + best_t * p_dir
	for axis in 3:
		if key[axis] == 0 and (hit[axis] < EDGE_MARGIN_M or hit[axis] > BOX_MAX[axis] - EDGE_MARGIN_M):
			return null
	return key


## The coloured room and a 64² RoomProbe at CENTRE feeding p_material, under _holder (hidden,
## outside the views' worlds: only the map matters), in the tree; fills by_normal. Returns the probe.
func _room_and_probe(p_material: ShaderMaterial, by_normal: Dictionary) -> Node:
	_holder = Node3D.new()
	_holder.visible = false
	_holder.add_child(_coloured_room(by_normal))
	var probe = ClassDB.instantiate("RoomProbe")
	probe.resolution = 64
	probe.position = CENTRE
	probe.target_material = p_material
	_holder.add_child(probe)
	probe.coarse_model = NodePath("../Room")
	add_to_tree(_holder)
	return probe


## A CoarseRoomModel of PLAN with one flat colour per surface; fills by_normal (colour by the
## direction from which a surface is seen, rounded).
func _coloured_room(by_normal: Dictionary) -> Node3D:
	var room = ClassDB.instantiate("CoarseRoomModel")
	room.name = "Room"
	room.floorplan = PackedVector2Array(PLAN)
	room.ceiling_height = HEIGHT
	room.texel_size = 0.05
	var size: Vector2i = room.get_atlas_size()
	var atlas := Image.create_empty(size.x, size.y, false, Image.FORMAT_RGBF)
	for c in room.get_charts():
		var color: Color = FLOOR_COLOR if c.kind == "floor" else CEILING_COLOR if c.kind == "ceiling" else WALL_COLORS[c.wall_index]
		atlas.fill_rect(c.rect, color)
		by_normal[Vector3i((-c.normal as Vector3).round())] = color
	assert_true(room.set_atlas_image(atlas))
	return room


## Which of the surface colours the pixel is nearest to, and how near.
func _nearest_surface(by_normal: Dictionary, got: Color) -> Array:
	var best := Color()
	var best_d := INF
	for k in by_normal:
		var c: Color = by_normal[k]
		var d := Vector3(c.r - got.r, c.g - got.g, c.b - got.b).length()
		if d < best_d:
			best_d = d
			best = c
	return [best, best_d]


## A chrome sphere with Godot's own StandardMaterial3D (no RoomProbe shader).
func _chrome() -> StandardMaterial3D:
	var m := StandardMaterial3D.new()
	m.metallic = 1.0
	m.roughness = 0.0
	m.metallic_specular = 0.5
	m.albedo_color = Color(1, 1, 1)
	return m


func test_reflection_probe_route_shows_the_room_on_a_standard_material() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	known_engine_leak(7, "Texture", "godotengine/godot#122498: each reflection atlas leaks 7 texture RIDs (4.6 regression)")
	var by_normal := {}
	# One world, centred on the sphere: the room (moved so that its centre is there) on layer 20
	# only, which the camera does not see and the probe does.
	_viewport = _make_view(_chrome(), Vector3(0, 0, 3), Vector3(0, 0, 0))
	var cam: Camera3D = _viewport.get_child(2)
	cam.cull_mask = 0xFFFFF & ~(1 << 19)
	var room := _coloured_room(by_normal)
	room.room_layers = 1 << 19
	room.position = -CENTRE
	_viewport.add_child(room)
	var reflection := ReflectionProbe.new()
	reflection.name = "Reflection"
	_viewport.add_child(reflection)
	var probe = ClassDB.instantiate("RoomProbe")
	probe.resolution = 16
	_viewport.add_child(probe)
	add_to_tree(_viewport)
	probe.coarse_model = probe.get_path_to(room)
	probe.reflection_probe = probe.get_path_to(reflection)
	assert_true(probe.update_now())
	assert_near(reflection.global_position + reflection.origin_offset, Vector3(), 0.001, "the capture point is the probe's")
	assert_near(reflection.size, Vector3(4, HEIGHT, 3), 0.001, "the box is the room's")
	assert_eq(reflection.cull_mask, 1 << 19, "the probe sees the room's layer only")
	assert_true(reflection.box_projection)
	await wait_frames(12)
	var img := _viewport.get_texture().get_image()
	if not artifacts_dir.is_empty():
		img.save_png(artifacts_dir.path_join("room_probe_reflection_probe_route.png"))
	var background := img.get_pixel(1, 1).srgb_to_linear()
	assert_true(background.get_luminance() < 0.02, "the camera does not see the room itself: %s" % background)
	# The sphere's centre reflects back towards the camera, towards +Z: the wall seen that way.
	var got := img.get_pixel(SIZE.x / 2, SIZE.y / 2).srgb_to_linear()
	var nearest := _nearest_surface(by_normal, got)
	assert_eq(nearest[0], by_normal[Vector3i(0, 0, 1)], "the chrome sphere shows the +Z wall (pixel %s)" % got)


func test_world_environment_route_lights_standard_materials_from_the_map() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	var by_normal := {}
	var probe = _probe_in_coloured_room(32, by_normal)
	_viewport = SubViewport.new()
	_viewport.size = Vector2i(4, 4)
	var vp := _make_view(_chrome(), Vector3(0, 0, 3), Vector3(0, 0, 0))
	_viewport.add_child(vp)
	add_to_tree(_viewport)
	var world_env: WorldEnvironment = vp.get_child(0)
	probe.world_environment = probe.get_path_to(world_env)
	assert_true(probe.update_now())
	assert_not_null(probe.get_sky_material(), "the sky material was made")
	assert_eq(world_env.environment.sky.sky_material, probe.get_sky_material())
	assert_eq(world_env.environment.reflected_light_source, Environment.REFLECTION_SOURCE_SKY)
	assert_eq(world_env.environment.background_mode, Environment.BG_COLOR, "the background is left alone")
	await wait_frames(8)
	var img := vp.get_texture().get_image()
	if not artifacts_dir.is_empty():
		img.save_png(artifacts_dir.path_join("room_probe_world_environment_route.png"))
	var got := img.get_pixel(SIZE.x / 2, SIZE.y / 2).srgb_to_linear()
	var nearest := _nearest_surface(by_normal, got)
	assert_eq(nearest[0], by_normal[Vector3i(0, 0, 1)], "the chrome sphere shows the +Z wall through the sky (pixel %s)" % got)


## A rough StandardMaterial3D lit through the sky route (Godot prefilters the probe's map into
## its own radiance maps, GGX with 32 samples) against rough_metal.gdshader reading RoomProbe's
## GGX chain (route a), white metal, at three roughnesses: the two are the same split-sum
## integral of the same map, so they differ only by the two filters' sampling and level spacing.
## The same comparison at a roughness 0.3 off must differ by more, or the test would not see a
## roughness convention that is wrong.
func test_rough_metal_matches_a_standard_material_at_the_same_roughness() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	if RenderingServer.get_current_rendering_method() == "mobile":
		# Measured on lavapipe: Mobile's own StandardMaterial3D reflects the same sky darker and
		# flatter than Forward+'s (its simplified environment specular), 0.42-1.5 from ours and
		# from Forward+'s alike: no like-for-like reference. The other Mobile tests still run.
		return skip("Mobile renderer: its StandardMaterial3D's environment specular is simplified, no reference to match")
	var probe = _probe_in_coloured_room(64, {})
	const ROUGHNESS := [0.25, 0.5, 0.8]
	_viewport = SubViewport.new()
	_viewport.size = Vector2i(4, 4)
	var standard_views: Array[SubViewport] = []
	var shader_views: Array[SubViewport] = []
	for r in ROUGHNESS:
		var m := _chrome()
		m.roughness = r
		var vp := _make_view(m, Vector3(0, 0, 3), Vector3(0, 0, 0))
		_viewport.add_child(vp)
		standard_views.append(vp)
	for r in ROUGHNESS + [0.55, 0.2, 0.5]:  # then each at a roughness 0.3 off
		var m := ShaderMaterial.new()
		m.shader = load("res://addons/roomprobe/shaders/rough_metal.gdshader")
		m.set_shader_parameter("tint", Vector3.ONE)
		m.set_shader_parameter("roughness", r)
		var vp := _make_view(m, Vector3(0, 0, 3), Vector3(0, 0, 0))
		_viewport.add_child(vp)
		shader_views.append(vp)
	add_to_tree(_viewport)
	probe.world_environment = probe.get_path_to(standard_views[0].get_child(0))
	assert_true(probe.update_now())
	var sky: Sky = (standard_views[0].get_child(0) as WorldEnvironment).environment.sky
	assert_not_null(sky, "the probe made the sky")
	for vp in standard_views.slice(1):
		var env := (vp.get_child(0) as WorldEnvironment).environment
		env.sky = sky
		env.reflected_light_source = Environment.REFLECTION_SOURCE_SKY
		env.ambient_light_source = Environment.AMBIENT_SOURCE_SKY  # as the probe sets it
	for vp in shader_views:
		((vp.get_child(1) as MeshInstance3D).material_override as ShaderMaterial).set_shader_parameter("environment", probe.get_cubemap())
	await wait_frames(12)
	var images: Array[Image] = []
	for vp in standard_views + shader_views:
		images.append(vp.get_texture().get_image())
	var differences: Array[float] = []
	for i in shader_views.size():
		var standard := images[i % ROUGHNESS.size()]
		var ours := images[ROUGHNESS.size() + i]
		if not artifacts_dir.is_empty() and i < ROUGHNESS.size():
			standard.save_png(artifacts_dir.path_join("rough_standard_%d.png" % i))
			ours.save_png(artifacts_dir.path_join("rough_metal_%d.png" % i))
		differences.append(_mean_relative_difference(standard, ours, 24))
	print("    rough metal against StandardMaterial3D, mean relative difference at roughness %s: %s; 0.3 off: %s" % [
			ROUGHNESS, differences.slice(0, 3), differences.slice(3)])
	for i in ROUGHNESS.size():
		assert_true(differences[i] < ROUGH_METAL_TOLERANCE, "roughness %.2f: rough_metal and StandardMaterial3D agree (%.3f)" % [ROUGHNESS[i], differences[i]])
		assert_true(differences[i + 3] > ROUGH_METAL_TOLERANCE, "roughness 0.3 off is told apart (%.3f)" % differences[i + 3])


## Over the disc of p_radius pixels at the image's centre: mean |a - b| (linear RGB) over the
## mean luminance of a.
func _mean_relative_difference(a: Image, b: Image, radius: int) -> float:
	var diff := 0.0
	var lum := 0.0
	for y in range(SIZE.y / 2 - radius, SIZE.y / 2 + radius + 1):
		for x in range(SIZE.x / 2 - radius, SIZE.x / 2 + radius + 1):
			if Vector2(x - SIZE.x / 2, y - SIZE.y / 2).length() > radius:
				continue
			var ca := a.get_pixel(x, y).srgb_to_linear()
			var cb := b.get_pixel(x, y).srgb_to_linear()
			diff += Vector3(ca.r - cb.r, ca.g - cb.g, ca.b - cb.b).length()
			lum += ca.get_luminance()
	return diff / maxf(lum, 1e-6)


## §4.7's last paragraph: a second virtual object (a magenta diffuse panel on a layer in the
## probe's virtual_objects_mask) between the probe and the +Z wall shows in the mirror sphere's
## reflection where that wall did; with the mask cleared the wall is back.
func test_mirror_sphere_shows_a_second_virtual_object() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	var by_normal := {}
	var probe = _probe_in_coloured_room(64, by_normal, true)
	var panel := MeshInstance3D.new()
	var panel_mesh := BoxMesh.new()
	panel_mesh.size = Vector3(1.2, 1.2, 0.05)
	panel.mesh = panel_mesh
	panel.position = CENTRE + Vector3(0, 0, 0.8)
	panel.layers = 1 << 10
	var magenta := StandardMaterial3D.new()
	magenta.albedo_color = Color(1, 0, 1)
	panel.material_override = magenta
	_holder.add_child(panel)
	probe.virtual_objects_mask = 1 << 10
	assert_true(probe.update_now())
	assert_eq(probe.get_virtual_object_count(), 1, "the panel is handed to the probe")
	var mirror := ShaderMaterial.new()
	mirror.shader = load("res://addons/roomprobe/shaders/mirror.gdshader")
	mirror.set_shader_parameter("environment", probe.get_cubemap())
	_viewport = _make_view(mirror, Vector3(0, 0, 3), Vector3(0, 0, 0))
	add_to_tree(_viewport)
	await wait_frames(4)
	var with_panel := _viewport.get_texture().get_image()
	probe.virtual_objects_mask = 0
	assert_true(probe.update_now())
	mirror.set_shader_parameter("environment", probe.get_cubemap())
	await wait_frames(4)
	var without := _viewport.get_texture().get_image()
	if not artifacts_dir.is_empty():
		with_panel.save_png(artifacts_dir.path_join("mirror_with_virtual_panel.png"))
	# The sphere's centre reflects towards +Z (the camera): the panel, magenta (lit by the room's
	# SH: red and blue well above green), where the +Z wall was.
	var got := with_panel.get_pixel(SIZE.x / 2, SIZE.y / 2).srgb_to_linear()
	assert_true(got.r > 4.0 * got.g and got.b > 4.0 * got.g and got.r > 0.05, "the mirror shows the magenta panel (pixel %s)" % got)
	var back := without.get_pixel(SIZE.x / 2, SIZE.y / 2).srgb_to_linear()
	assert_eq(_nearest_surface(by_normal, back)[0], by_normal[Vector3i(0, 0, 1)], "without it, the +Z wall (pixel %s)" % back)


## _holder: the coloured room and a RoomProbe of p_resolution at its CENTRE, in the tree, the
## probe rendering that room. p_by_normal gets the surfaces' colours; p_visible false keeps the
## room out of the main viewport (a virtual object the probe draws must be visible).
func _probe_in_coloured_room(p_resolution: int, p_by_normal: Dictionary, p_visible := false) -> Node:
	_holder = Node3D.new()
	_holder.visible = p_visible
	_holder.add_child(_coloured_room(p_by_normal))
	var probe = ClassDB.instantiate("RoomProbe")
	probe.name = "Probe"
	probe.resolution = p_resolution
	probe.position = CENTRE
	_holder.add_child(probe)
	add_to_tree(_holder)
	probe.coarse_model = NodePath("../Room")
	return probe


func _make_view(material: Material, cam_position: Vector3, cam_rotation: Vector3, sphere_position := Vector3.ZERO, sphere_radius := 0.8) -> SubViewport:
	var vp := SubViewport.new()
	vp.size = SIZE
	vp.own_world_3d = true
	vp.render_target_update_mode = SubViewport.UPDATE_ALWAYS
	var env := Environment.new()
	env.background_mode = Environment.BG_COLOR
	env.background_color = Color(0, 0, 0)
	var world_env := WorldEnvironment.new()
	world_env.environment = env
	vp.add_child(world_env)
	var sphere_mesh := SphereMesh.new()
	sphere_mesh.radius = sphere_radius
	sphere_mesh.height = 2.0 * sphere_radius
	sphere_mesh.radial_segments = 128
	sphere_mesh.rings = 64
	var sphere := MeshInstance3D.new()
	sphere.mesh = sphere_mesh
	sphere.material_override = material
	sphere.position = sphere_position
	vp.add_child(sphere)
	var cam := Camera3D.new()
	cam.fov = 40
	cam.position = cam_position
	cam.rotation_degrees = cam_rotation
	cam.current = true
	vp.add_child(cam)
	return vp


## A sphere lit through its PRT transfer (prt_diffuse.gdshader) against the same sphere shaded
## by the SH irradiance at its normals (sh_diffuse.gdshader): a convex mesh shadows
## nothing, so both are albedo / pi times the same irradiance, and any slip in the transfer's
## layout, its VERTEX_ID lookup or the SH convention shows as a difference.
func test_prt_sphere_matches_the_sh_diffuse_shading() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	var probe = _probe_in_coloured_room(64, {})
	assert_true(probe.update_now())
	var sphere_mesh := SphereMesh.new()
	sphere_mesh.radius = 0.8
	sphere_mesh.height = 1.6
	var prt = ClassDB.instantiate("PRTTransfer")
	prt.mesh = sphere_mesh
	prt.samples_per_vertex = 1024
	assert_true(prt.bake(), prt.get_last_error())
	var prt_material := ShaderMaterial.new()
	prt_material.shader = load("res://addons/roomprobe/shaders/prt_diffuse.gdshader")
	prt_material.set_shader_parameter("transfer", prt.get_transfer_texture())
	prt_material.set_shader_parameter("sh", probe.get_sh_coefficients())
	prt_material.set_shader_parameter("albedo", Color(0.95, 0.64, 0.54))
	var sh_material := ShaderMaterial.new()
	sh_material.shader = load("res://addons/roomprobe/shaders/sh_diffuse.gdshader")
	sh_material.set_shader_parameter("sh", probe.get_sh_coefficients())
	sh_material.set_shader_parameter("albedo", Color(0.95, 0.64, 0.54))
	# The same sphere turned: its transfer is in the mesh's frame, so it needs the light in that
	# frame (get_sh_coefficients_in); with the world's SH it must be visibly wrong.
	const TURN := Vector3(40, 70, 0)
	var turned_basis := Basis.from_euler(TURN * PI / 180.0)
	var turned_material := prt_material.duplicate() as ShaderMaterial
	turned_material.set_shader_parameter("sh", probe.get_sh_coefficients_in(turned_basis))
	var unrotated_light := prt_material.duplicate() as ShaderMaterial
	_viewport = SubViewport.new()
	_viewport.size = Vector2i(4, 4)
	var shots: Array[SubViewport] = []
	for material in [prt_material, sh_material, turned_material, unrotated_light]:
		var vp := _make_view(material, Vector3(0, 0, 3), Vector3(0, 0, 0))
		var sphere := vp.get_child(1) as MeshInstance3D
		sphere.mesh = sphere_mesh
		if material == turned_material or material == unrotated_light:
			sphere.basis = turned_basis
		_viewport.add_child(vp)
		shots.append(vp)
	add_to_tree(_viewport)
	await wait_frames(4)
	var images: Array[Image] = []
	for vp in shots:
		images.append(vp.get_texture().get_image())
	if not artifacts_dir.is_empty():
		images[0].save_png(artifacts_dir.path_join("prt_sphere.png"))
		images[1].save_png(artifacts_dir.path_join("sh_sphere.png"))
		images[2].save_png(artifacts_dir.path_join("prt_sphere_turned.png"))
	var worst := [0.0, 0.0, 0.0]  # PRT, turned PRT with its light turned, turned PRT with the world's light
	for p in [Vector2i(48, 48), Vector2i(48, 30), Vector2i(48, 66), Vector2i(30, 48), Vector2i(66, 48)]:
		var b := images[1].get_pixelv(p).srgb_to_linear()
		assert_true(b.get_luminance() > 0.05, "the SH sphere is lit at %s: %s" % [p, b])
		for k in 3:
			var a := images[[0, 2, 3][k]].get_pixelv(p).srgb_to_linear()
			worst[k] = maxf(worst[k], Vector3(a.r - b.r, a.g - b.g, a.b - b.b).length() / maxf(b.get_luminance(), 1e-3))
	print("    PRT sphere against the SH-shaded sphere: worst relative difference %.3f; turned %.3f; turned without turning the light %.3f" % worst)
	# Per-vertex (PRT) against per-pixel (SH) shading of a 64-segment sphere, 8-bit output: a few %.
	assert_true(worst[0] < 0.05, "PRT and SH shading agree (%.3f)" % worst[0])
	assert_true(worst[1] < 0.05, "a turned PRT object lit in its own frame agrees too (%.3f)" % worst[1])
	assert_true(worst[2] > 0.1, "a turned PRT object lit with the world's SH does not (%.3f)" % worst[2])


## The table under a PRT object is darker than beside it: a grey "table" (standing in for the
## camera image) under contact_shadow.gdshader's plane, the plane's transfer baked with a sphere
## resting on it as the occluder, lit by a uniform sky; seen from above without the sphere.
func test_contact_shadow_darkens_the_table_under_the_object() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	var plane := PlaneMesh.new()
	plane.size = Vector2(2, 2)
	plane.subdivide_width = 31
	plane.subdivide_depth = 31
	var sphere := SphereMesh.new()
	sphere.radius = 0.25
	sphere.height = 0.5
	var prt = ClassDB.instantiate("PRTTransfer")
	prt.mesh = plane
	prt.occluder = sphere
	prt.occluder_transform = Transform3D(Basis(), Vector3(0, 0.25, 0))
	prt.samples_per_vertex = 256
	assert_true(prt.bake(), prt.get_last_error())
	var sky := PackedVector3Array()
	sky.resize(25)
	sky[0] = Vector3.ONE * sqrt(4.0 * PI)  # radiance 1 from everywhere
	var shadow := ShaderMaterial.new()
	shadow.shader = load("res://addons/roomprobe/shaders/contact_shadow.gdshader")
	shadow.set_shader_parameter("transfer", prt.get_transfer_texture())
	shadow.set_shader_parameter("sh", sky)
	var table_material := StandardMaterial3D.new()
	table_material.shading_mode = BaseMaterial3D.SHADING_MODE_UNSHADED
	table_material.albedo_color = Color(0.7, 0.7, 0.7)
	_viewport = SubViewport.new()
	_viewport.size = SIZE
	_viewport.own_world_3d = true
	_viewport.render_target_update_mode = SubViewport.UPDATE_ALWAYS
	var table := MeshInstance3D.new()
	table.mesh = plane
	table.material_override = table_material
	_viewport.add_child(table)
	var catcher := MeshInstance3D.new()
	catcher.mesh = plane
	catcher.material_override = shadow
	catcher.position = Vector3(0, 0.001, 0)
	catcher.sorting_offset = 1.0  # after the table
	_viewport.add_child(catcher)
	var cam := Camera3D.new()
	cam.projection = Camera3D.PROJECTION_ORTHOGONAL
	cam.size = 2.0
	cam.position = Vector3(0, 3, 0)
	cam.rotation_degrees = Vector3(-90, 0, 0)
	cam.current = true
	_viewport.add_child(cam)
	add_to_tree(_viewport)
	await wait_frames(4)
	var img := _viewport.get_texture().get_image()
	if not artifacts_dir.is_empty():
		img.save_png(artifacts_dir.path_join("contact_shadow.png"))
	var centre := img.get_pixel(SIZE.x / 2, SIZE.y / 2).srgb_to_linear().get_luminance()
	var near := img.get_pixel(SIZE.x / 2 + 12, SIZE.y / 2).srgb_to_linear().get_luminance()  # 0.25 m: one radius out
	var beside := img.get_pixel(4, 4).srgb_to_linear().get_luminance()
	print("    table luminance: under the sphere %.3f, one radius out %.3f, beside %.3f" % [centre, near, beside])
	assert_near(beside, Color(0.7, 0.7, 0.7).srgb_to_linear().get_luminance(), 0.03, "beside the object the table is as it was")
	assert_true(centre < 0.5 * beside, "under the object the table is darker (%.3f against %.3f)" % [centre, beside])
	# One radius out the analytic ratio is 1 - (1/sqrt(2))^3 = 0.65 (the mesh's vertices, 6.5 cm apart, interpolate it).
	assert_near(near / beside, 0.65, 0.08, "one radius from the contact")
