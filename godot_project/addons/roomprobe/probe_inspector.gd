@tool
extends EditorInspectorPlugin
## RoomProbe's inspector: a preview of its last environment map as a cross of the six faces
## (RoomProbe.get_net_image: +Y on top, then -X, +Z, +X, -Z, then -Y), with an Update button.

const PREVIEW_NAME := "RoomProbeCubemapPreview"


func _can_handle(object: Object) -> bool:
	return object != null and object.is_class("RoomProbe")


func _parse_begin(object: Object) -> void:
	var box := VBoxContainer.new()
	box.name = PREVIEW_NAME
	var picture := TextureRect.new()
	picture.name = "Cross"
	picture.stretch_mode = TextureRect.STRETCH_KEEP_ASPECT_CENTERED
	picture.expand_mode = TextureRect.EXPAND_IGNORE_SIZE
	picture.custom_minimum_size = Vector2(0, 150)
	var label := Label.new()
	label.name = "Status"
	var button := Button.new()
	button.text = "Update map now"
	var refresh := func():
		var cross: Image = object.get_net_image()
		picture.texture = ImageTexture.create_from_image(cross) if cross else null
		label.text = "Environment map %dx%d a face" % [cross.get_width() / 4, cross.get_width() / 4] if cross else "No map yet (the probe has not rendered one)"
	button.pressed.connect(func():
		object.update_now()
		refresh.call())
	refresh.call()
	box.add_child(label)
	box.add_child(picture)
	box.add_child(button)
	add_custom_control(box)
