class_name FigureMeshes
extends RefCounted
## Procedural meshes for the demo scenes that reproduce the paper's figures.
##
## Units are metres, Y up; every mesh rests on y = 0 and is centred on x = z = 0. Each is one
## surface of triangles with outward normals, smooth within each part, wound as Godot's own
## primitive meshes (SphereMesh): clockwise seen from outside. Parts may overlap one another,
## but each is a closed surface.
##
## - teapot(): a bulging body and a lid with a knob (surfaces of revolution), a tapering spout
##   towards +x and a C-shaped handle towards -x (tubes swept along curves, both ends inside
##   the body). Wider than tall.
## - water_bottle(): one closed surface of revolution, a plastic bottle: push-up base, ribbed
##   body, shoulder, neck, collar ring and cap. No water inside.
## - mannequin(): an artist's wooden mannequin of ellipsoids, capsules and sphere joints, standing
##   relaxed (arms a little out, its left elbow bent forward), facing +z, on a round base disc.


## The one surface being built: every part appends its vertices, normals and triangles here,
## in unit coordinates that to_mesh() scales to metres.
class _Parts:
	var vertices := PackedVector3Array()
	var normals := PackedVector3Array()
	var indices := PackedInt32Array()

	## Appends a grid of vertices (row-major, cols to a row) and two triangles per cell. Rows run
	## along the part and columns around it such that d(row) x d(column) points outwards.
	func add_grid(points: PackedVector3Array, point_normals: PackedVector3Array, cols: int) -> void:
		var base := vertices.size()
		vertices.append_array(points)
		normals.append_array(point_normals)
		for i in points.size() / cols - 1:
			for j in cols - 1:
				var a := base + i * cols + j
				var b := a + cols  # the same column, next row
				# Godot's front faces are clockwise seen from outside (as its SphereMesh's):
				# each triangle is wound so that (v1 - v0) x (v2 - v0) points inwards.
				_add_triangle(a, a + 1, b)
				_add_triangle(a + 1, b + 1, b)

	## Leaves out the zero-area triangles where a row collapses onto a pole (cos(PI / 2) is not
	## quite 0, hence a threshold rather than equality).
	func _add_triangle(a: int, b: int, c: int) -> void:
		var doubled_area := (vertices[b] - vertices[a]).cross(vertices[c] - vertices[a]).length()
		if doubled_area > 1e-9:
			indices.append_array(PackedInt32Array([a, b, c]))

	## The mesh, scaled by scale and lifted by lift (in unit coordinates) along Y.
	func to_mesh(scale: float, lift: float = 0.0) -> ArrayMesh:
		var placed := PackedVector3Array()
		placed.resize(vertices.size())
		for i in vertices.size():
			placed[i] = (vertices[i] + Vector3(0.0, lift, 0.0)) * scale
		var arrays := []
		arrays.resize(Mesh.ARRAY_MAX)
		arrays[Mesh.ARRAY_VERTEX] = placed
		arrays[Mesh.ARRAY_NORMAL] = normals
		arrays[Mesh.ARRAY_INDEX] = indices
		var mesh := ArrayMesh.new()
		mesh.add_surface_from_arrays(Mesh.PRIMITIVE_TRIANGLES, arrays)
		return mesh


# --- the meshes ------------------------------------------------------------------------------


## A teapot height_m tall (knob included), spout towards +x, handle towards -x; detail is the
## number of segments around each part.
static func teapot(height_m: float = 0.16, detail: int = 32) -> ArrayMesh:
	var parts := _Parts.new()
	var rows := maxi(detail / 2, 4)
	# Body, in units of the height: a flat foot, widest a third of the way up, its top closed
	# under the lid's rim.
	var body := PackedVector2Array([Vector2(0.0, 0.0), Vector2(0.18, 0.0), Vector2(0.32, 0.0), Vector2(0.355, 0.006)])
	_append_bezier(body, Vector2(0.37, 0.02), Vector2(0.58, 0.04), Vector2(0.60, 0.55), Vector2(0.36, 0.70), rows)
	body.append_array(PackedVector2Array([Vector2(0.34, 0.71), Vector2(0.17, 0.71), Vector2(0.0, 0.71)]))
	_lathe(parts, body, detail)
	# Lid: its underside inside the body, a rim overhanging the opening, a dome, then the knob,
	# a ball on a short neck whose top is the teapot's top.
	var lid := PackedVector2Array([Vector2(0.0, 0.675), Vector2(0.2, 0.675), Vector2(0.33, 0.675), Vector2(0.35, 0.69),
			Vector2(0.38, 0.70), Vector2(0.385, 0.71), Vector2(0.375, 0.72)])
	_append_bezier(lid, Vector2(0.36, 0.725), Vector2(0.33, 0.80), Vector2(0.16, 0.83), Vector2(0.06, 0.835), rows)
	lid.append_array(PackedVector2Array([Vector2(0.045, 0.845), Vector2(0.04, 0.865)]))
	var knob_rows := maxi(detail / 3, 3)
	for i in knob_rows + 1:
		var angle := lerpf(deg_to_rad(-40.0), PI / 2.0, float(i) / knob_rows)
		lid.append(Vector2(0.0, 0.935) + 0.065 * Vector2(cos(angle), sin(angle)))
	lid[lid.size() - 1] = Vector2(0.0, 1.0)  # exactly on the axis and at the top
	_lathe(parts, lid, detail)
	# Spout: from well inside the body, out and up to a narrow tip at about the lid's height.
	var spout := _bezier_points(Vector3(0.36, 0.24, 0.0), Vector3(0.64, 0.22, 0.0), Vector3(0.66, 0.52, 0.0),
			Vector3(0.88, 0.75, 0.0), detail * 3 / 4)
	var spout_radii := PackedFloat32Array()
	for i in spout.size():
		var t := float(i) / (spout.size() - 1)
		spout_radii.append(0.04 + 0.11 * (1.0 - t) * (1.0 - t))
	_tube(parts, spout, spout_radii, detail)
	# Handle: a C from the upper body out to -x and back into the lower body.
	var handle := _bezier_points(Vector3(-0.36, 0.60, 0.0), Vector3(-0.95, 0.72, 0.0), Vector3(-0.92, 0.12, 0.0),
			Vector3(-0.44, 0.24, 0.0), detail)
	var handle_radii := PackedFloat32Array()
	handle_radii.resize(handle.size())
	handle_radii.fill(0.038)
	_tube(parts, handle, handle_radii, detail)
	return parts.to_mesh(height_m)


## A plastic water bottle height_m tall (cap included), about a quarter as wide; detail is the
## number of segments around it.
static func water_bottle(height_m: float = 0.24, detail: int = 48) -> ArrayMesh:
	const R := 0.14  # the body's radius, in units of the height
	var rows := maxi(detail / 8, 3)
	var p := PackedVector2Array()
	# A push-up base: the centre raised a little, the bottle standing on a ring.
	for i in rows:
		var r := 0.7 * R * i / rows
		p.append(Vector2(r, 0.012 * (1.0 - pow(r / (0.7 * R), 2.0))))
	for i in rows + 1:  # the rounded edge of the base
		var angle := lerpf(-PI / 2.0, 0.0, float(i) / rows)
		p.append(Vector2(R - 0.03, 0.03) + 0.03 * Vector2(cos(angle), sin(angle)))
	# Body: straight, then a band of grip grooves.
	p.append_array(PackedVector2Array([Vector2(R, 0.12), Vector2(R, 0.22), Vector2(R, 0.30)]))
	const GROOVES := 5
	for i in range(1, GROOVES * rows + 1):
		var u := float(i) / (GROOVES * rows)
		p.append(Vector2(R * (1.0 - 0.04 * pow(sin(PI * GROOVES * u), 2.0)), lerpf(0.30, 0.55, u)))
	# Shoulder down to the neck, the collar ring below the cap, the cap with a rounded top edge.
	p.append(Vector2(R, 0.60))
	_append_bezier(p, Vector2(R, 0.62), Vector2(R, 0.73), Vector2(0.056, 0.76), Vector2(0.056, 0.84), 2 * rows)
	p.append_array(PackedVector2Array([Vector2(0.056, 0.865), Vector2(0.072, 0.868), Vector2(0.076, 0.874),
			Vector2(0.072, 0.880), Vector2(0.056, 0.883), Vector2(0.056, 0.888), Vector2(0.064, 0.890),
			Vector2(0.066, 0.896), Vector2(0.066, 0.94)]))
	for i in rows + 1:
		var angle := lerpf(0.0, PI / 2.0, float(i) / rows)
		p.append(Vector2(0.056, 0.99) + 0.01 * Vector2(cos(angle), sin(angle)))
	p.append_array(PackedVector2Array([Vector2(0.028, 1.0), Vector2(0.0, 1.0)]))
	var parts := _Parts.new()
	_lathe(parts, p, detail)
	return parts.to_mesh(height_m)


## An artist's wooden mannequin height_m tall (base disc included), facing +z; detail is the
## number of segments around each part.
static func mannequin(height_m: float = 0.30, detail: int = 16) -> ArrayMesh:
	# In units of the figure's height: soles at y = 0, the head's top at 1, its left towards +x,
	# on a disc BASE thick below y = 0.
	const BASE := 0.04
	var parts := _Parts.new()
	_lathe(parts, PackedVector2Array([Vector2(0.0, -BASE), Vector2(0.09, -BASE), Vector2(0.16, -BASE),
			Vector2(0.17, -0.75 * BASE), Vector2(0.17, -0.25 * BASE), Vector2(0.16, 0.0), Vector2(0.09, 0.0),
			Vector2(0.0, 0.0)]), detail)
	# Head, neck, chest (broad at the shoulders), waist joint, pelvis.
	_ellipsoid(parts, Vector3(0.056, 0.07, 0.064), Transform3D(Basis.IDENTITY, Vector3(0.0, 0.93, 0.005)), detail)
	_capsule(parts, Vector3(0.0, 0.82, 0.0), Vector3(0.0, 0.885, 0.0), 0.027, 0.024, detail)
	_ellipsoid(parts, Vector3(0.12, 0.11, 0.07), Transform3D(Basis.IDENTITY, Vector3(0.0, 0.73, 0.0)), detail)
	_sphere(parts, Vector3(0.0, 0.61, 0.0), 0.055, detail)
	_ellipsoid(parts, Vector3(0.10, 0.075, 0.068), Transform3D(Basis.IDENTITY, Vector3(0.0, 0.52, 0.0)), detail)
	# Legs: hip, knee, ankle; its right knee a little forward, the weight on its left leg.
	var leg_radii := PackedFloat32Array([0.048, 0.036, 0.026])
	var legs := [PackedVector3Array([Vector3(-0.06, 0.49, 0.0), Vector3(-0.068, 0.27, 0.025), Vector3(-0.08, 0.055, 0.0)]),
			PackedVector3Array([Vector3(0.06, 0.49, 0.0), Vector3(0.064, 0.27, 0.0), Vector3(0.066, 0.055, -0.005)])]
	for leg: PackedVector3Array in legs:
		_limb(parts, leg, leg_radii, detail)
		var ankle := leg[2]
		_ellipsoid(parts, Vector3(0.03, 0.022, 0.062), Transform3D(Basis.IDENTITY, Vector3(ankle.x, 0.022, ankle.z + 0.03)), detail)
	# Arms: shoulder, elbow, wrist; the right one hanging a little away from the body, the left
	# one bent at the elbow, its forearm reaching forwards.
	var arm_radii := PackedFloat32Array([0.034, 0.026, 0.018])
	var arms := [PackedVector3Array([Vector3(-0.12, 0.80, 0.0), Vector3(-0.16, 0.635, -0.01), Vector3(-0.18, 0.48, 0.01)]),
			PackedVector3Array([Vector3(0.12, 0.80, 0.0), Vector3(0.16, 0.635, -0.015), Vector3(0.17, 0.56, 0.125)])]
	for arm: PackedVector3Array in arms:
		_limb(parts, arm, arm_radii, detail)
		var forearm := (arm[2] - arm[1]).normalized()
		# A flat hand along the forearm, the palm towards the body.
		_ellipsoid(parts, Vector3(0.012, 0.045, 0.024), _frame_along(arm[2] + 0.05 * forearm, forearm), detail)
	return parts.to_mesh(height_m / (1.0 + BASE), BASE)


# --- parts -----------------------------------------------------------------------------------


## Appends the surface of revolution about the Y axis of profile (x: radius, y: height), placed
## by xform. The profile runs from pole to pole with the solid on its left (bottom pole first
## for an upright part). Normals: profile_normals where given, else from the profile's tangent.
static func _lathe(parts: _Parts, profile: PackedVector2Array, segments: int,
		xform: Transform3D = Transform3D.IDENTITY, profile_normals: PackedVector2Array = PackedVector2Array()) -> void:
	var normals_2d := profile_normals if not profile_normals.is_empty() else _profile_normals(profile)
	var normal_basis := xform.basis.inverse().transposed()  # normals under a non-uniform scale
	var points := PackedVector3Array()
	var normals := PackedVector3Array()
	for i in profile.size():
		for j in segments + 1:  # the last column repeats the first: the seam
			var angle := TAU * j / segments
			var radial := Vector3(cos(angle), 0.0, sin(angle))
			points.append(xform * (radial * profile[i].x + Vector3.UP * profile[i].y))
			normals.append((normal_basis * (radial * normals_2d[i].x + Vector3.UP * normals_2d[i].y)).normalized())
	parts.add_grid(points, normals, segments + 1)


## Outward normals of a profile, from its tangent by central differences; vertical on the axis,
## so that a pole shades without a pinch.
static func _profile_normals(profile: PackedVector2Array) -> PackedVector2Array:
	var out := PackedVector2Array()
	var last := profile.size() - 1
	for i in profile.size():
		var tangent := profile[mini(i + 1, last)] - profile[maxi(i - 1, 0)]
		var normal := Vector2(tangent.y, -tangent.x)
		if profile[i].x == 0.0:
			normal.x = 0.0
		out.append(normal.normalized())
	return out


## Appends an ellipsoid with semi-axes radii along xform's axes, centred at its origin.
static func _ellipsoid(parts: _Parts, radii: Vector3, xform: Transform3D, segments: int) -> void:
	var profile := PackedVector2Array()
	var rows := maxi(segments / 2, 2)
	for i in rows + 1:
		var angle := PI * (float(i) / rows - 0.5)
		profile.append(Vector2(cos(angle), sin(angle)))
	# On the unit sphere the normal is the point itself; _lathe carries it through the scale.
	_lathe(parts, profile, segments, xform * Transform3D(Basis.from_scale(radii), Vector3.ZERO), profile)


static func _sphere(parts: _Parts, centre: Vector3, radius: float, segments: int) -> void:
	_ellipsoid(parts, Vector3.ONE * radius, Transform3D(Basis.IDENTITY, centre), segments)


## Appends a capsule from a to b whose radius goes from radius_a to radius_b: a sphere at each
## end and the cone tangent to both between them.
static func _capsule(parts: _Parts, a: Vector3, b: Vector3, radius_a: float, radius_b: float, segments: int) -> void:
	var length := a.distance_to(b)
	# The latitude at which the cone touches both spheres.
	var touch := asin(clampf((radius_a - radius_b) / length, -1.0, 1.0))
	var profile := PackedVector2Array()
	var normals := PackedVector2Array()
	var rows := maxi(segments / 4, 2)
	for i in 2 * rows + 2:
		var on_b := i > rows
		var k := i - rows - 1 if on_b else i
		var angle := lerpf(touch, PI / 2.0, float(k) / rows) if on_b else lerpf(-PI / 2.0, touch, float(k) / rows)
		var normal := Vector2(cos(angle), sin(angle))
		if on_b and k == 0:
			# Rings along the cone too: per-vertex data (a PRT transfer) needs vertices there, as
			# the end caps are mostly hidden inside the joints.
			var cone_rows := maxi(segments / 2, 2)
			for j in range(1, cone_rows):
				var t := float(j) / cone_rows
				profile.append(normal * lerpf(radius_a, radius_b, t) + Vector2(0.0, length * t))
				normals.append(normal)
		profile.append(normal * radius_b + Vector2(0.0, length) if on_b else normal * radius_a)
		normals.append(normal)
	_lathe(parts, profile, segments, _frame_along(a, b - a), normals)


## Appends a limb: a sphere at each joint, of joint_radii, and between consecutive joints a
## capsule a little thinner than them, so that the joints stand out as on a wooden mannequin.
static func _limb(parts: _Parts, joints: PackedVector3Array, joint_radii: PackedFloat32Array, segments: int) -> void:
	for i in joints.size():
		_sphere(parts, joints[i], joint_radii[i], segments)
		if i > 0:
			_capsule(parts, joints[i - 1], joints[i], 0.8 * joint_radii[i - 1], 0.8 * joint_radii[i], segments)


## Appends a tube along centreline, of radius radii[i] at its point i, closed by a half sphere
## at each end.
static func _tube(parts: _Parts, centreline: PackedVector3Array, radii: PackedFloat32Array, segments: int) -> void:
	var count := centreline.size()
	var last := count - 1
	var points := PackedVector3Array()
	var normals := PackedVector3Array()
	var cap_rows := maxi(segments / 4, 2)
	var tangent := (centreline[1] - centreline[0]).normalized()
	var side := tangent.cross(Vector3.UP if absf(tangent.y) < 0.9 else Vector3.RIGHT).normalized()
	# The cap at the start, from its pole to the first ring.
	for k in cap_rows:
		var angle := PI / 2.0 * (1.0 - float(k) / cap_rows)
		_ring(points, normals, centreline[0] - tangent * radii[0] * sin(angle), tangent, side, radii[0] * cos(angle),
				Vector2(cos(angle), -sin(angle)), segments)
	for i in count:
		var span := centreline[mini(i + 1, last)] - centreline[maxi(i - 1, 0)]
		tangent = span.normalized()
		# The side vector projected onto each new ring's plane: a frame that follows the curve
		# without twisting (nearly parallel transport for small steps).
		side = (side - tangent * side.dot(tangent)).normalized()
		# Where the tube narrows its surface leans forwards: tilt the normal by the taper.
		var taper := (radii[mini(i + 1, last)] - radii[maxi(i - 1, 0)]) / span.length()
		_ring(points, normals, centreline[i], tangent, side, radii[i], Vector2(1.0, -taper).normalized(), segments)
	for k in range(1, cap_rows + 1):
		var angle := PI / 2.0 * float(k) / cap_rows
		_ring(points, normals, centreline[last] + tangent * radii[last] * sin(angle), tangent, side,
				radii[last] * cos(angle), Vector2(cos(angle), sin(angle)), segments)
	parts.add_grid(points, normals, segments + 1)


## Appends one ring of a tube: centre, the tube's direction there, a unit vector across it,
## its radius, and its normal as (outwards, along the tangent) components.
static func _ring(points: PackedVector3Array, normals: PackedVector3Array, centre: Vector3, tangent: Vector3,
		side: Vector3, radius: float, normal: Vector2, segments: int) -> void:
	var binormal := tangent.cross(side)
	for j in segments + 1:
		var angle := TAU * j / segments
		# This sense of rotation makes d(along) x d(around) point outwards, as add_grid needs.
		var radial := binormal * cos(angle) + side * sin(angle)
		points.append(centre + radial * radius)
		normals.append((radial * normal.x + tangent * normal.y).normalized())


# --- curves ----------------------------------------------------------------------------------


## A transform whose Y axis is axis (normalised), at origin: a lathed part along a direction.
static func _frame_along(origin: Vector3, axis: Vector3) -> Transform3D:
	var y := axis.normalized()
	var x := y.cross(Vector3.FORWARD if absf(y.z) < 0.9 else Vector3.RIGHT).normalized()
	return Transform3D(Basis(x, y, x.cross(y)), origin)


## Point t of the cubic Bezier curve p0..p3 (Vector2 or Vector3).
static func _bezier(p0: Variant, p1: Variant, p2: Variant, p3: Variant, t: float) -> Variant:
	var s := 1.0 - t
	return s * s * s * p0 + 3.0 * s * s * t * p1 + 3.0 * s * t * t * p2 + t * t * t * p3


## Appends the cubic Bezier p0..p3 to a profile in steps + 1 points, p0 and p3 included.
static func _append_bezier(profile: PackedVector2Array, p0: Vector2, p1: Vector2, p2: Vector2, p3: Vector2, steps: int) -> void:
	for i in steps + 1:
		profile.append(_bezier(p0, p1, p2, p3, float(i) / steps))


## The cubic Bezier p0..p3 as a centreline of steps + 1 points.
static func _bezier_points(p0: Vector3, p1: Vector3, p2: Vector3, p3: Vector3, steps: int) -> PackedVector3Array:
	var out := PackedVector3Array()
	for i in steps + 1:
		out.append(_bezier(p0, p1, p2, p3, float(i) / steps))
	return out
