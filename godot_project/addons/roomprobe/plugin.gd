@tool
extends EditorPlugin
## RoomProbe's editor plugin: adds the PRTTransfer inspector (a Bake button with progress).

var _inspector: EditorInspectorPlugin


func _enter_tree() -> void:
	_inspector = preload("res://addons/roomprobe/prt_inspector.gd").new()
	add_inspector_plugin(_inspector)


func _exit_tree() -> void:
	remove_inspector_plugin(_inspector)
	_inspector = null
