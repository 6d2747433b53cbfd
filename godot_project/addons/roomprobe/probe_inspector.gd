@tool
extends EditorInspectorPlugin
## RoomProbe's inspector: a preview of its last environment map as a cross of the six faces
## (+Y on top, then -X, +Z, +X, -Z, then -Y), with an Update button.

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
		var cross := cross_image(object)
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


## The six faces as one 4x3 cross image, or null before the first map.
static func cross_image(probe: Object) -> Image:
	var faces: Array[Image] = []
	for face in 6:
		var image: Image = probe.get_face_image(face)
		if image == null or image.is_empty():
			return null
		image = image.duplicate()
		if image.get_format() != Image.FORMAT_RGBAH:
			image.convert(Image.FORMAT_RGBAH)
		faces.append(image)
	var n := faces[0].get_width()
	var cross := Image.create_empty(4 * n, 3 * n, false, Image.FORMAT_RGBAH)
	cross.fill(Color(0.15, 0.15, 0.15, 1.0))
	# Godot's face order: +X, -X, +Y, -Y, +Z, -Z; the cross's cell of each.
	var cells := [Vector2i(2, 1), Vector2i(0, 1), Vector2i(1, 0), Vector2i(1, 2), Vector2i(1, 1), Vector2i(3, 1)]
	for face in 6:
		cross.blit_rect(faces[face], Rect2i(0, 0, n, n), cells[face] * n)
	# The maps are linear HDR: shown clamped and sRGB-encoded for the eye.
	cross.convert(Image.FORMAT_RGBA8)
	cross.linear_to_srgb()
	return cross
