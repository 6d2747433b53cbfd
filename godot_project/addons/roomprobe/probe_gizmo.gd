@tool
extends EditorNode3DGizmoPlugin
## The gizmo of RoomProbe: three circles around the point its maps are rendered at, so the probe
## can be seen and picked in the viewport (it has no mesh of its own).

const RADIUS_M := 0.15


func _init() -> void:
	create_material("probe", Color(1.0, 0.8, 0.3))


func _get_gizmo_name() -> String:
	return "RoomProbe"


func _has_gizmo(node: Node3D) -> bool:
	return node.is_class("RoomProbe")


func _redraw(gizmo: EditorNode3DGizmo) -> void:
	gizmo.clear()
	var lines := PackedVector3Array()
	const STEPS := 32
	for axis in 3:
		for i in STEPS:
			for k in [i, i + 1]:
				var a: float = TAU * float(k) / STEPS
				var p := Vector2(cos(a), sin(a)) * RADIUS_M
				lines.append([Vector3(p.x, p.y, 0), Vector3(p.x, 0, p.y), Vector3(0, p.x, p.y)][axis])
	gizmo.add_lines(lines, get_material("probe", gizmo))
	gizmo.add_collision_segments(lines)
