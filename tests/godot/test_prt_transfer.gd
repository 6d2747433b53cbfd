extends RoomProbeTestCase
## PRTTransfer through Godot (paper §4.8): the transfer of Godot's own meshes, in their vertex
## order, laid out as prt_diffuse.gdshader reads it; the cache; the resource saved and loaded; a
## clear error for what cannot be baked.

const Y00 := 0.28209479177387814  # y_0^0 = 1 / (2 sqrt(pi))


## Band 0 of vertex v's transfer, where the shader reads it.
static func _band0(p_image: Image, p_vertex: int) -> float:
	return p_image.get_pixel((p_vertex % 256) * 7, p_vertex / 256).r


func _sphere() -> SphereMesh:
	var sphere := SphereMesh.new()
	sphere.radius = 0.5
	sphere.height = 1.0
	sphere.radial_segments = 24
	sphere.rings = 12
	return sphere


func test_a_sphere_sees_the_whole_lobe_and_the_layout_follows_its_vertices() -> void:
	var prt = ClassDB.instantiate("PRTTransfer")
	prt.mesh = _sphere()
	prt.samples_per_vertex = 1024
	assert_false(prt.is_baked(), "nothing baked yet")
	assert_true(prt.bake(), prt.get_last_error())
	var vertices: int = prt.mesh.surface_get_arrays(0)[Mesh.ARRAY_VERTEX].size()
	assert_eq(prt.get_vertex_count(), vertices)
	var image: Image = prt.transfer
	assert_eq(image.get_format(), Image.FORMAT_RGBAF)
	assert_eq(image.get_width(), 256 * 7)
	assert_eq(image.get_height(), (vertices + 255) / 256)
	# A convex mesh shadows nothing: band 0 is pi * y_0^0 at every vertex (exact with
	# cosine-weighted directions).
	for v in vertices:
		assert_near(_band0(image, v), PI * Y00, 1e-4, "vertex %d" % v)
	assert_true(prt.get_last_bake_rays() == vertices * 1024, str(prt.get_last_bake_rays()))
	print("    sphere, %d vertices at %d samples: %.3f ms a vertex" % [vertices, prt.samples_per_vertex, 1000.0 * prt.get_last_bake_seconds() / vertices])
	assert_not_null(prt.get_transfer_texture())


func test_a_torus_is_darker_on_its_inside_and_the_cache_holds_until_the_mesh_changes() -> void:
	var torus := TorusMesh.new()
	torus.inner_radius = 0.3
	torus.outer_radius = 0.6
	var prt = ClassDB.instantiate("PRTTransfer")
	prt.mesh = torus
	prt.samples_per_vertex = 256
	assert_true(prt.bake(), prt.get_last_error())
	var image: Image = prt.transfer
	var darkest := INF
	var brightest := 0.0
	for v in prt.get_vertex_count():
		darkest = minf(darkest, _band0(image, v))
		brightest = maxf(brightest, _band0(image, v))
	# The hole's side sees the ring across it; the outer side sees the whole lobe.
	assert_near(brightest, PI * Y00, 0.02 * PI * Y00, "the outside is unshadowed")
	assert_true(darkest < 0.8 * PI * Y00, "the inside is shadowed (%.3f)" % darkest)
	# Unchanged: the cache is used.
	assert_true(prt.is_baked())
	assert_true(prt.bake())
	assert_eq(prt.get_last_bake_rays(), 0, "nothing traced the second time")
	# Changed settings or mesh: not baked any more.
	prt.samples_per_vertex = 512
	assert_false(prt.is_baked())
	prt.samples_per_vertex = 256
	assert_true(prt.is_baked())
	torus.rings = 20
	assert_false(prt.is_baked(), "a changed mesh needs a new bake")


func test_saved_and_loaded_it_keeps_its_transfer_and_key() -> void:
	var prt = ClassDB.instantiate("PRTTransfer")
	prt.mesh = _sphere()
	prt.samples_per_vertex = 64
	assert_true(prt.bake(), prt.get_last_error())
	var path := "user://test_prt_transfer.res"
	assert_eq(ResourceSaver.save(prt, path), OK)
	var loaded = ResourceLoader.load(path, "", ResourceLoader.CACHE_MODE_IGNORE)
	DirAccess.remove_absolute(ProjectSettings.globalize_path(path))
	assert_not_null(loaded)
	assert_eq(loaded.cache_key, prt.cache_key)
	assert_true(loaded.is_baked(), "the loaded transfer still belongs to its mesh")
	assert_near(_band0(loaded.transfer, 5), _band0(prt.transfer, 5), 1e-6)


func test_what_cannot_be_baked_says_why() -> void:
	var prt = ClassDB.instantiate("PRTTransfer")
	expect_error("PRTTransfer: no mesh")
	assert_false(prt.bake())
	assert_eq(prt.get_last_error(), "PRTTransfer: no mesh")
	prt.mesh = _sphere()
	prt.surface = 3
	expect_error("PRTTransfer: the mesh has no surface 3 (it has 1)")
	assert_false(prt.bake())
	prt.samples_per_vertex = -5
	assert_eq(prt.samples_per_vertex, 16, "clamped to the range")


func test_the_shader_takes_the_transfer_and_the_probe_sh() -> void:
	var shader: Shader = load("res://addons/roomprobe/shaders/prt_diffuse.gdshader")
	assert_not_null(shader)
	var names := shader.get_shader_uniform_list().map(func(u): return u.name)
	for name in ["transfer", "sh", "albedo"]:
		assert_true(name in names, "uniform %s in %s" % [name, names])


func test_an_occluder_shadows_a_plane_under_it_and_is_part_of_the_key() -> void:
	var plane := PlaneMesh.new()
	plane.size = Vector2(4, 4)
	plane.subdivide_width = 15
	plane.subdivide_depth = 15
	var sphere := _sphere()
	var prt = ClassDB.instantiate("PRTTransfer")
	prt.mesh = plane
	prt.samples_per_vertex = 1024
	assert_true(prt.bake(), prt.get_last_error())
	var free_key: String = prt.cache_key
	prt.occluder = sphere
	prt.occluder_transform = Transform3D(Basis(), Vector3(0, 0.5, 0))  # resting on the plane at its centre
	assert_false(prt.is_baked(), "a new occluder needs a new bake")
	assert_true(prt.bake(), prt.get_last_error())
	assert_ne(prt.cache_key, free_key)
	# Under a uniform sky band 0 is the irradiance: the vertex nearest the contact is darkened by
	# about the analytic 1 - (R / D)^3, the plane's corners are not.
	var arrays: Array = plane.surface_get_arrays(0)
	var positions: PackedVector3Array = arrays[Mesh.ARRAY_VERTEX]
	var nearest := 0
	var corner := 0
	for v in positions.size():
		if Vector2(positions[v].x, positions[v].z).length() < Vector2(positions[nearest].x, positions[nearest].z).length():
			nearest = v
		if Vector2(positions[v].x, positions[v].z).length() > Vector2(positions[corner].x, positions[corner].z).length():
			corner = v
	var d := Vector2(positions[nearest].x, positions[nearest].z).length()
	var expected := 1.0 - pow(0.5 / sqrt(d * d + 0.25), 3.0)
	var image: Image = prt.transfer
	assert_near(_band0(image, nearest) / (PI * Y00), expected, 0.03, "the contact's ratio at %.3f m" % d)
	assert_near(_band0(image, corner) / (PI * Y00), 1.0, 0.01, "a corner 2.8 m away is unshadowed")
