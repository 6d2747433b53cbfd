@tool
extends EditorNode3DGizmoPlugin
## The floorplan gizmo of CoarseRoomModel: the room's prism as lines (floor, ceiling, the walls'
## vertical edges) and a handle at each floor corner. Dragging a handle moves that corner on the
## floor plane (local Y = 0); the move is one undoable action.

var _undo: EditorUndoRedoManager


func _init(undo: EditorUndoRedoManager = null) -> void:
	_undo = undo
	create_material("walls", Color(0.35, 0.8, 1.0))
	create_material("invalid", Color(1.0, 0.35, 0.3))
	create_handle_material("corners")


func _get_gizmo_name() -> String:
	return "CoarseRoomModel floorplan"


func _has_gizmo(node: Node3D) -> bool:
	return node.is_class("CoarseRoomModel")


func _redraw(gizmo: EditorNode3DGizmo) -> void:
	gizmo.clear()
	var room := gizmo.get_node_3d()
	var plan: PackedVector2Array = room.floorplan
	if plan.is_empty():
		return
	var height: float = room.ceiling_height if is_finite(room.ceiling_height) and room.ceiling_height > 0.0 else 0.0
	var lines := PackedVector3Array()
	var handles := PackedVector3Array()
	for i in plan.size():
		var a := Vector3(plan[i].x, 0.0, plan[i].y)
		var b := Vector3(plan[(i + 1) % plan.size()].x, 0.0, plan[(i + 1) % plan.size()].y)
		var up := Vector3(0.0, height, 0.0)
		lines.append_array([a, b, a + up, b + up, a, a + up])
		handles.append(a)
	gizmo.add_lines(lines, get_material("walls" if room.is_valid() else "invalid", gizmo))
	gizmo.add_handles(handles, get_material("corners", gizmo), PackedInt32Array())


func _get_handle_name(_gizmo: EditorNode3DGizmo, handle_id: int, _secondary: bool) -> String:
	return "Corner %d" % handle_id


func _get_handle_value(gizmo: EditorNode3DGizmo, handle_id: int, _secondary: bool) -> Variant:
	return gizmo.get_node_3d().floorplan[handle_id]


func _set_handle(gizmo: EditorNode3DGizmo, handle_id: int, _secondary: bool, camera: Camera3D, screen_pos: Vector2) -> void:
	var room := gizmo.get_node_3d()
	var corner = floor_point(room, camera.project_ray_origin(screen_pos), camera.project_ray_normal(screen_pos))
	if corner != null:
		move_corner(room, handle_id, corner)


func _commit_handle(gizmo: EditorNode3DGizmo, handle_id: int, _secondary: bool, restore: Variant, cancel: bool) -> void:
	var room := gizmo.get_node_3d()
	var moved: PackedVector2Array = room.floorplan
	var before := moved.duplicate()
	before[handle_id] = restore
	if cancel or _undo == null:
		if cancel:
			room.floorplan = before
		return
	_undo.create_action("Move floorplan corner %d" % handle_id)
	_undo.add_do_property(room, "floorplan", moved)
	_undo.add_undo_property(room, "floorplan", before)
	_undo.commit_action(false)  # already done while dragging


## Where a ray (global space) meets the room's floor plane, as a floorplan point (x, z), or null.
static func floor_point(room: Node3D, origin: Vector3, direction: Vector3) -> Variant:
	var to_local := room.global_transform.affine_inverse()
	var o := to_local * origin
	var d := to_local.basis * direction
	if absf(d.y) < 1e-6:
		return null
	var t := -o.y / d.y
	if t < 0.0:
		return null
	var hit := o + d * t
	return Vector2(hit.x, hit.z)


## Sets corner index of the room's floorplan (a new array, as the setter wants).
static func move_corner(room: Node3D, index: int, corner: Vector2) -> void:
	var plan: PackedVector2Array = room.floorplan
	if index < 0 or index >= plan.size():
		return
	plan[index] = corner
	room.floorplan = plan
