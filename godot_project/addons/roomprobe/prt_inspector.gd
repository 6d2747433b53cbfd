@tool
extends EditorInspectorPlugin
## A "Bake transfer" button at the top of a PRTTransfer's inspector. The bake runs on the main
## thread (PRTTransfer.bake()) with print_progress on, so its progress lines go to the Output
## panel; the result (vertices, time, rays) or the error shows under the button. An unchanged
## mesh with unchanged settings is not baked again (the cache key).


func _can_handle(object: Object) -> bool:
	return object != null and object.get_class() == "PRTTransfer"


func _parse_begin(object: Object) -> void:
	var box := VBoxContainer.new()
	var button := Button.new()
	button.text = "Bake transfer"
	button.tooltip_text = "Precompute the mesh's shadowed 5-band transfer with Embree rays (PRTTransfer.bake())."
	var status := Label.new()
	status.autowrap_mode = TextServer.AUTOWRAP_WORD_SMART
	status.text = _describe(object)
	button.pressed.connect(_bake.bind(object, status))
	box.add_child(button)
	box.add_child(status)
	add_custom_control(box)


func _bake(transfer: Object, status: Label) -> void:
	var was_printing: bool = transfer.print_progress
	transfer.print_progress = true
	var ok: bool = transfer.bake()
	transfer.print_progress = was_printing
	status.text = _describe(transfer) if ok else "Bake failed: %s" % transfer.get_last_error()


func _describe(transfer: Object) -> String:
	if not transfer.is_baked():
		return "Not baked (%d vertices)." % transfer.get_vertex_count()
	return "Baked: %d vertices; last bake %.2f s, %d rays." % [transfer.get_vertex_count(), transfer.get_last_bake_seconds(), transfer.get_last_bake_rays()]
