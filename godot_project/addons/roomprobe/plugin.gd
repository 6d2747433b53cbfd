@tool
extends EditorPlugin
## RoomProbe's editor plugin: the PRTTransfer inspector (a Bake button with progress), RoomProbe's
## map preview in the inspector, CoarseRoomModel's "Find the room in the recording" button, the floorplan gizmo of CoarseRoomModel (draggable corners) and
## the gizmo of RoomProbe.

var _inspectors: Array[EditorInspectorPlugin] = []
var _gizmos: Array[EditorNode3DGizmoPlugin] = []


func _enter_tree() -> void:
	_inspectors = [preload("res://addons/roomprobe/prt_inspector.gd").new(), preload("res://addons/roomprobe/probe_inspector.gd").new(),
			preload("res://addons/roomprobe/room_inspector.gd").new()]
	for inspector in _inspectors:
		add_inspector_plugin(inspector)
	_gizmos = [preload("res://addons/roomprobe/floorplan_gizmo.gd").new(get_undo_redo()), preload("res://addons/roomprobe/probe_gizmo.gd").new()]
	for gizmo in _gizmos:
		add_node_3d_gizmo_plugin(gizmo)


func _exit_tree() -> void:
	for inspector in _inspectors:
		remove_inspector_plugin(inspector)
	for gizmo in _gizmos:
		remove_node_3d_gizmo_plugin(gizmo)
	_inspectors.clear()
	_gizmos.clear()
