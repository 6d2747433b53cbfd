@tool
extends EditorInspectorPlugin
## A "Find the room in the recording" button at the top of a CoarseRoomModel's inspector (issue
## #18): the room of its RigCapture's recording is found on a worker thread (about a minute for a
## 10-s sweep, as ./roomprobe room), and the editor then shows it: the node's floorplan, ceiling
## height and transform are set to the room found (saved with the scene). The label says what was
## found, or what is missing. Not undoable: set floorplan_source back and retype to undo.


func _can_handle(object: Object) -> bool:
	return object != null and object.get_class() == "CoarseRoomModel"


func _parse_begin(object: Object) -> void:
	var box := VBoxContainer.new()
	var button := Button.new()
	button.text = "Find the room in the recording"
	button.tooltip_text = "Find the floorplan, ceiling height and the room's place from the RigCapture's recording (CoarseRoomModel.find_room_in_recording())."
	var status := Label.new()
	status.autowrap_mode = TextServer.AUTOWRAP_WORD_SMART
	status.text = _describe(object)
	button.disabled = object.is_finding_room()
	button.pressed.connect(func():
		if object.find_room_in_recording(""):
			button.disabled = true
			status.text = "Searching the recording for the room (the dense model first, then the walls and the ceiling)...")
	var on_estimate := func(state: String, message: String):
		if is_instance_valid(button):
			button.disabled = false
			status.text = "%s: %s" % [state.capitalize(), message]
	object.room_estimated.connect(on_estimate, CONNECT_ONE_SHOT)
	box.add_child(button)
	box.add_child(status)
	add_custom_control(box)


func _describe(room: Object) -> String:
	if room.is_finding_room():
		return "Searching the recording for the room..."
	var estimate: Dictionary = room.get_room_estimate()
	if estimate.is_empty():
		return "Finds the room from the RigCapture's recording: no floorplan or tape measure needed."
	return "%s: %s" % [String(estimate.state).capitalize(), estimate.message]
