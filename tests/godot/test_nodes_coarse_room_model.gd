extends RoomProbeTestCase
## CoarseRoomModel through Godot: the room mesh for the paper's Figure-4 floorplan (two rooms
## partly separated by a partition) is closed and its UV charts do not overlap; invalid
## floorplans give warnings that say what is wrong.

# The paper's Figure 4: an 8 m x 4.5 m room with a 0.12 m partition 3 m long at x = 4.
const FIGURE4 := [Vector2(0, 0), Vector2(3.94, 0), Vector2(3.94, 3), Vector2(4.06, 3),
		Vector2(4.06, 0), Vector2(8, 0), Vector2(8, 4.5), Vector2(0, 4.5)]
const HEIGHT := 2.6

var _room  # CoarseRoomModel


func before_each() -> void:
	_room = ClassDB.instantiate("CoarseRoomModel")
	_room.floorplan = PackedVector2Array(FIGURE4)
	_room.ceiling_height = HEIGHT


func after_each() -> void:
	if is_instance_valid(_room):
		_room.free()
	_room = null


func _arrays() -> Array:
	var mesh: ArrayMesh = _room.get_mesh()
	return mesh.surface_get_arrays(0)


func _area(poly: Array) -> float:
	var a := 0.0
	for i in poly.size():
		var p: Vector2 = poly[i]
		var q: Vector2 = poly[(i + 1) % poly.size()]
		a += p.x * q.y - q.x * p.y
	return absf(a) * 0.5


func test_figure4_mesh_is_closed() -> void:
	assert_true(_room.is_valid(), "Figure 4 is a valid floorplan: %s" % _room.get_floorplan_error())
	var arrays := _arrays()
	var verts: PackedVector3Array = arrays[Mesh.ARRAY_VERTEX]
	var idx: PackedInt32Array = arrays[Mesh.ARRAY_INDEX]
	assert_eq(idx.size() % 3, 0)
	# Weld positions (vertices are duplicated per UV chart), then every directed edge must be
	# matched by exactly one opposite edge: closed and consistently oriented.
	var key_of := {}
	var ids := PackedInt32Array()
	for v in verts:
		var k := Vector3i(roundi(v.x * 1000), roundi(v.y * 1000), roundi(v.z * 1000))
		if not key_of.has(k):
			key_of[k] = key_of.size()
		ids.append(key_of[k])
	var edges := {}
	for t in range(0, idx.size(), 3):
		for e in 3:
			var a := ids[idx[t + e]]
			var b := ids[idx[t + (e + 1) % 3]]
			var k := Vector2i(a, b)
			edges[k] = edges.get(k, 0) + 1
	var unmatched := 0
	for k in edges:
		if edges[k] != 1 or edges.get(Vector2i(k.y, k.x), 0) != 1:
			unmatched += 1
	assert_eq(unmatched, 0, "every edge is shared by exactly two triangles, in opposite directions")
	# Euler characteristic of a closed genus-0 surface: V - E + F = 2.
	assert_eq(key_of.size() - edges.size() / 2 + idx.size() / 3, 2, "V - E + F")
	# Enclosed volume by the divergence theorem equals floor area x height.
	var volume := 0.0
	for t in range(0, idx.size(), 3):
		volume += verts[idx[t]].dot(verts[idx[t + 1]].cross(verts[idx[t + 2]])) / 6.0
	assert_near(absf(volume), _area(FIGURE4) * HEIGHT, 1e-3, "volume")


func test_figure4_uv_charts_do_not_overlap() -> void:
	var arrays := _arrays()
	var uvs: PackedVector2Array = arrays[Mesh.ARRAY_TEX_UV]
	var idx: PackedInt32Array = arrays[Mesh.ARRAY_INDEX]
	var atlas: Vector2i = _room.get_atlas_size()
	assert_true(atlas.x > 0 and atlas.y > 0, "atlas size %s" % atlas)
	# Group triangles into charts by shared UV vertices, then rasterise each chart's triangles
	# at texel centres; no texel may belong to two charts.
	var parent := range(uvs.size())
	var find := func(i):
		while parent[i] != i:
			i = parent[i]
		return i
	for t in range(0, idx.size(), 3):
		for e in [1, 2]:
			var a = find.call(idx[t])
			var b = find.call(idx[t + e])
			if a != b:
				parent[b] = a
	var owner := {}
	var overlaps := 0
	for t in range(0, idx.size(), 3):
		var chart = find.call(idx[t])
		var p: Array[Vector2] = []
		for k in 3:
			var uv: Vector2 = uvs[idx[t + k]]
			assert_true(uv.x >= 0.0 and uv.x <= 1.0 and uv.y >= 0.0 and uv.y <= 1.0, "UV inside [0, 1]")
			p.append(uv * Vector2(atlas))
		var lo := Vector2i(floori(minf(p[0].x, minf(p[1].x, p[2].x))), floori(minf(p[0].y, minf(p[1].y, p[2].y))))
		var hi := Vector2i(ceili(maxf(p[0].x, maxf(p[1].x, p[2].x))), ceili(maxf(p[0].y, maxf(p[1].y, p[2].y))))
		for y in range(lo.y, hi.y):
			for x in range(lo.x, hi.x):
				var c := Vector2(x + 0.5, y + 0.5)
				if Geometry2D.point_is_inside_triangle(c, p[0], p[1], p[2]):
					var k := y * atlas.x + x
					if owner.has(k) and owner[k] != chart:
						overlaps += 1
					owner[k] = chart
	assert_eq(overlaps, 0, "texels covered by two charts")
	# Walls (one per edge), floor and ceiling.
	var charts := {}
	for i in uvs.size():
		charts[find.call(i)] = true
	assert_eq(charts.size(), FIGURE4.size() + 2, "one chart per wall, plus floor and ceiling")


func test_invalid_floorplans_warn_and_say_why() -> void:
	var cases := {
		"self-intersecting": [PackedVector2Array([Vector2(0, 0), Vector2(4, 3), Vector2(4, 0), Vector2(0, 3)]), 2.5],
		"fewer than 3 points": [PackedVector2Array([Vector2(0, 0), Vector2(1, 0)]), 2.5],
		"zero area": [PackedVector2Array([Vector2(0, 0), Vector2(1, 0), Vector2(2, 0)]), 2.5],
		# 100000 points once held the main thread for minutes: refused at once (issue #17).
		"too many points": [_circle(100000), 2.5],
	}
	for expected in cases:
		_room.floorplan = cases[expected][0]
		_room.ceiling_height = cases[expected][1]
		assert_false(_room.is_valid(), "%s is rejected" % expected)
		assert_eq(_room.get_mesh().get_surface_count(), 0, "%s leaves no mesh" % expected)
		var text := " ".join(_room.get_warnings())
		assert_true(text.to_lower().contains(expected), "warning for %s says so: %s" % [expected, text])
	# A ceiling at the floor is clamped to the lowest the property takes (issue #38's sweep).
	_room.floorplan = PackedVector2Array(FIGURE4)
	expect_warning("CoarseRoomModel.ceiling_height must be within [0.5, 100] m; got 0")
	_room.ceiling_height = 0.0
	assert_eq(_room.ceiling_height, 0.5)
	_room.ceiling_height = HEIGHT
	assert_true(_room.is_valid(), "valid again after the fix")
	assert_eq(_room.get_mesh().get_surface_count(), 1)


## p_count points on a 2-m circle: a valid polygon of any size.
func _circle(p_count: int) -> PackedVector2Array:
	var points := PackedVector2Array()
	points.resize(p_count)
	for i in p_count:
		points[i] = Vector2(2.0 * cos(TAU * i / p_count), 2.0 * sin(TAU * i / p_count))
	return points


func test_mesh_follows_edits_live() -> void:
	var changes := [0]
	_room.mesh_changed.connect(func(): changes[0] += 1)
	add_to_tree(_room)
	await wait_frames(1)
	var before: int = _arrays()[Mesh.ARRAY_VERTEX].size()
	var plan: PackedVector2Array = _room.floorplan
	plan.insert(6, Vector2(8, 2))  # one more corner on the far wall
	_room.floorplan = plan
	assert_true(changes[0] >= 1, "mesh_changed was emitted")
	assert_eq(_arrays()[Mesh.ARRAY_VERTEX].size(), before + 6, "six more vertices: one more wall, and its corners on floor and ceiling")
	var shown: MeshInstance3D = null
	for c in _room.get_children(true):
		if c is MeshInstance3D:
			shown = c
	assert_not_null(shown, "an internal MeshInstance3D shows the room")
	if shown:
		assert_eq(shown.mesh, _room.get_mesh(), "it shows the model's mesh")
		assert_null(shown.owner, "it is not saved with the scene")


func test_every_node_registers_and_reports_what_it_cannot_do() -> void:
	for c in ["RigCapture", "DenseSLAM", "CoarseRoomModel", "RoomProbe"]:
		assert_true(ClassDB.class_exists(c), c)
		var n = ClassDB.instantiate(c)
		var warnings: PackedStringArray = n.get_warnings()
		# A new node is wired to nothing: each says what it needs.
		assert_false(warnings.is_empty(), "a new %s says what it needs" % c)
		n.free()
