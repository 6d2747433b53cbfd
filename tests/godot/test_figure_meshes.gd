extends RoomProbeTestCase
## The procedural meshes of the paper's figures (demo_scenes/figures/figure_meshes.gd): one
## surface each, consistent arrays, unit outward normals wound as Godot's own SphereMesh, no
## degenerate triangles, resting on y = 0 at the requested height, plausible proportions.

const Meshes := preload("res://demo_scenes/figures/figure_meshes.gd")


## Sign of (b - a) x (c - a) against the triangle's averaged normal, per triangle: +1 or -1.
static func _winding_signs(arrays: Array) -> PackedInt32Array:
	var v: PackedVector3Array = arrays[Mesh.ARRAY_VERTEX]
	var n: PackedVector3Array = arrays[Mesh.ARRAY_NORMAL]
	var idx: PackedInt32Array = arrays[Mesh.ARRAY_INDEX]
	var signs := PackedInt32Array()
	for t in range(0, idx.size(), 3):
		var a := idx[t]
		var b := idx[t + 1]
		var c := idx[t + 2]
		var face := (v[b] - v[a]).cross(v[c] - v[a])
		signs.append(1 if face.dot(n[a] + n[b] + n[c]) > 0.0 else -1)
	return signs


## Godot's convention, from its SphereMesh: the sign that (nearly) all its triangles share.
static func _godot_winding() -> int:
	var total := 0
	for s in _winding_signs(SphereMesh.new().get_mesh_arrays()):
		total += s
	return signi(total)


## Edges (u, v) of the triangles, u and v welded by position, with no partner (v, u): zero
## when every part is closed and consistently wound (seams and poles repeat positions).
static func _unpaired_edges(v: PackedVector3Array, idx: PackedInt32Array) -> int:
	var welded := {}
	var ids := PackedInt32Array()
	for p in v:
		var key := Vector3i((p * 1e6).round())
		if not welded.has(key):
			welded[key] = welded.size()
		ids.append(welded[key])
	var edges := {}
	for t in range(0, idx.size(), 3):
		for k in 3:
			var edge := Vector2i(ids[idx[t + k]], ids[idx[t + (k + 1) % 3]])
			edges[edge] = edges.get(edge, 0) + 1
	var unpaired := 0
	for edge: Vector2i in edges:
		if edges[edge] != edges.get(Vector2i(edge.y, edge.x), 0):
			unpaired += 1
	return unpaired


## The volume the surface encloses, counted positive for Godot's winding (clockwise seen from
## outside); overlapping parts add up.
static func _volume(v: PackedVector3Array, idx: PackedInt32Array) -> float:
	var volume := 0.0
	for t in range(0, idx.size(), 3):
		volume -= v[idx[t]].dot(v[idx[t + 1]].cross(v[idx[t + 2]])) / 6.0
	return volume


## The checks every figure mesh passes; returns its bounding box.
func _check_mesh(mesh: ArrayMesh, height: float, label: String) -> AABB:
	assert_eq(mesh.get_surface_count(), 1, label + ": one surface")
	assert_eq(mesh.surface_get_primitive_type(0), Mesh.PRIMITIVE_TRIANGLES, label + ": triangles")
	var arrays := mesh.surface_get_arrays(0)
	var v: PackedVector3Array = arrays[Mesh.ARRAY_VERTEX]
	var n: PackedVector3Array = arrays[Mesh.ARRAY_NORMAL]
	var idx: PackedInt32Array = arrays[Mesh.ARRAY_INDEX]
	assert_eq(n.size(), v.size(), label + ": a normal per vertex")
	assert_eq(idx.size() % 3, 0, label + ": whole triangles")
	print("    %s: %d vertices, %d triangles" % [label, v.size(), idx.size() / 3])
	var out_of_range := 0
	for i in idx:
		if i < 0 or i >= v.size():
			out_of_range += 1
	assert_eq(out_of_range, 0, label + ": indices in range")
	var not_unit := 0
	for normal in n:
		if absf(normal.length() - 1.0) > 1e-3:
			not_unit += 1
	assert_eq(not_unit, 0, label + ": unit normals")
	var box := mesh.get_aabb()
	assert_near(box.position.y, 0.0, 1e-4, label + ": resting on y = 0")
	assert_near(box.end.y, height, 0.02 * height, label + ": the requested height")
	var degenerate := 0
	for t in range(0, idx.size(), 3):
		if 0.5 * (v[idx[t + 1]] - v[idx[t]]).cross(v[idx[t + 2]] - v[idx[t]]).length() <= 1e-10:
			degenerate += 1
	assert_eq(degenerate, 0, label + ": no degenerate triangles")
	var godot := _godot_winding()
	var agree := 0
	var signs := _winding_signs(arrays)
	for s in signs:
		if s == godot:
			agree += 1
	assert_true(agree >= 0.95 * signs.size(), "%s: %d of %d triangles wound as SphereMesh's" % [label, agree, signs.size()])
	assert_eq(_unpaired_edges(v, idx), 0, label + ": closed parts, consistently wound")
	# Wound as Godot's front faces and enclosing a positive volume: facing outwards, and with
	# the winding agreeing with the normals, so are they.
	assert_true(_volume(v, idx) > 0.0, "%s: faces outwards (volume %.2f cm^3)" % [label, 1e6 * _volume(v, idx)])
	return box


## The larger of the footprint's two sides.
static func _width(box: AABB) -> float:
	return maxf(box.size.x, box.size.z)


func test_godot_sphere_mesh_has_one_winding() -> void:
	# The reference itself: if SphereMesh mixed windings the checks below would mean nothing.
	var signs := _winding_signs(SphereMesh.new().get_mesh_arrays())
	var total := 0
	for s in signs:
		total += s
	assert_eq(absi(total), signs.size(), "every SphereMesh triangle wound the same way")
	# And _volume() counts its winding positive, which the outward check below relies on.
	var arrays := SphereMesh.new().get_mesh_arrays()
	assert_true(_volume(arrays[Mesh.ARRAY_VERTEX], arrays[Mesh.ARRAY_INDEX]) > 0.0, "SphereMesh encloses a positive volume")


func test_teapot() -> void:
	var mesh := Meshes.teapot(0.16, 32)
	var box := _check_mesh(mesh, 0.16, "teapot")
	var vertices := mesh.surface_get_array_len(0)
	assert_true(vertices >= 3000 and vertices <= 12000, "teapot vertices at detail 32: %d" % vertices)
	assert_true(box.size.x > box.size.y, "spout and handle make it wider than tall: %s" % box.size)
	assert_near(box.position.z + box.end.z, 0.0, 1e-3, "centred on z = 0")


func test_water_bottle() -> void:
	var mesh := Meshes.water_bottle(0.24, 48)
	var box := _check_mesh(mesh, 0.24, "water bottle")
	assert_true(box.size.y > 2.5 * _width(box), "a slender bottle: %s" % box.size)
	# A half-litre bottle, as the profile's dimensions make it (about 0.45 l).
	var arrays := mesh.surface_get_arrays(0)
	var litres := 1000.0 * _volume(arrays[Mesh.ARRAY_VERTEX], arrays[Mesh.ARRAY_INDEX])
	assert_true(litres > 0.3 and litres < 0.7, "about half a litre: %.3f l" % litres)
	assert_near(box.get_center().x, 0.0, 1e-3, "centred on x = 0")
	assert_near(box.get_center().z, 0.0, 1e-3, "centred on z = 0")


func test_mannequin() -> void:
	var mesh := Meshes.mannequin(0.30, 16)
	var box := _check_mesh(mesh, 0.30, "mannequin")
	var vertices := mesh.surface_get_array_len(0)
	assert_true(vertices >= 3000 and vertices <= 10000, "mannequin vertices at detail 16: %d" % vertices)
	assert_true(box.size.y > 2.0 * _width(box), "a standing figure: %s" % box.size)


func test_other_sizes_scale_the_same_shapes() -> void:
	# Height and detail are parameters: a larger, coarser teapot keeps its proportions.
	_check_mesh(Meshes.teapot(0.5, 12), 0.5, "teapot 0.5 m, detail 12")
	_check_mesh(Meshes.water_bottle(1.0, 16), 1.0, "water bottle 1 m, detail 16")
	_check_mesh(Meshes.mannequin(0.2, 8), 0.2, "mannequin 0.2 m, detail 8")
