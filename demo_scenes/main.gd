extends Node3D
## RoomProbe's demo scene: a room from the paper's Figure-4 floor plan (when the extension
## provides CoarseRoomModel), a mirror sphere and a reflection probe, plus a printed report
## of what the RoomProbe extension registered.
##
## User arguments (after --):
##   --frames N          quit after N frames (at a frame boundary); default: run until closed
##   --screenshot PATH   save the viewport to PATH (PNG) after a few frames, then quit
##   --no-report         do not print the class report

const EXTENSION_CLASSES: Array[StringName] = [&"RigCapture", &"DenseSLAM", &"CoarseRoomModel", &"RoomProbe"]

## The two-room floor plan of the paper's Figure 4, in metres: an 8 m x 4.5 m outline split by
## a 0.12 m thick partition at x = 4 that runs 3 m in from the long wall at y = 0, leaving a
## 1.5 m opening between the rooms. Counter-clockwise, as seen with +y up.
const FIGURE4_FLOORPLAN: PackedVector2Array = [
	Vector2(0.0, 0.0), Vector2(3.94, 0.0), Vector2(3.94, 3.0), Vector2(4.06, 3.0),
	Vector2(4.06, 0.0), Vector2(8.0, 0.0), Vector2(8.0, 4.5), Vector2(0.0, 4.5),
]
const CEILING_HEIGHT := 2.6
const SCREENSHOT_FRAMES := 30

var _quit_after_frames := -1
var _screenshot_path := ""
var _frames := 0
var _room: Node


func _ready() -> void:
	var args := OS.get_cmdline_user_args()
	var report := not args.has("--no-report")
	for i in args.size():
		if args[i] == "--frames" and i + 1 < args.size():
			_quit_after_frames = args[i + 1].to_int()
		elif args[i] == "--screenshot" and i + 1 < args.size():
			_screenshot_path = args[i + 1]
	if report:
		print_report()
	_room = _make_room()


func _process(_delta: float) -> void:
	_frames += 1
	if not _screenshot_path.is_empty() and _frames == SCREENSHOT_FRAMES:
		_save_screenshot(_screenshot_path)
		get_tree().quit(0)
	elif _quit_after_frames >= 0 and _frames >= _quit_after_frames:
		get_tree().quit(0)


func _make_room() -> Node:
	if not ClassDB.class_exists(&"CoarseRoomModel") or not ClassDB.can_instantiate(&"CoarseRoomModel"):
		print("demo: CoarseRoomModel is not available; showing the sphere only")
		return null
	var room: Object = ClassDB.instantiate(&"CoarseRoomModel")
	if not room is Node:
		print("demo: CoarseRoomModel is not a Node (%s); not added to the scene" % room.get_class())
		if not room is RefCounted:
			room.free()
		return null
	room.name = "CoarseRoomModel"
	_set_if_present(room, &"floorplan", FIGURE4_FLOORPLAN)
	_set_if_present(room, &"ceiling_height", CEILING_HEIGHT)
	add_child(room)
	return room


static func _set_if_present(obj: Object, prop: StringName, value: Variant) -> void:
	for p in obj.get_property_list():
		if p.name == prop:
			obj.set(prop, value)
			return
	print("demo: %s has no property '%s'" % [obj.get_class(), prop])


func _save_screenshot(path: String) -> void:
	var tex := get_viewport().get_texture()
	var img := tex.get_image() if tex != null else null
	if img == null or img.is_empty():
		printerr("demo: no image to save (is there a renderer?)")
		return
	DirAccess.make_dir_recursive_absolute(path.get_base_dir())
	var err := img.save_png(path)
	if err == OK:
		print("demo: screenshot saved to %s (%dx%d)" % [path, img.get_width(), img.get_height()])
	else:
		printerr("demo: saving %s failed: %s" % [path, error_string(err)])


# --- the report -----------------------------------------------------------------------------


func print_report() -> void:
	print("RoomProbe demo: Godot %s, renderer %s (%s), display %s" % [
		Engine.get_version_info().string,
		RenderingServer.get_current_rendering_method(),
		RenderingServer.get_current_rendering_driver_name(),
		DisplayServer.get_name()])
	for cls in EXTENSION_CLASSES:
		_report_class(cls)


func _report_class(cls: StringName) -> void:
	print("")
	if not ClassDB.class_exists(cls):
		print("%s: not registered (is the RoomProbe extension built and loaded?)" % cls)
		return
	print("%s extends %s" % [cls, ClassDB.get_parent_class(cls)])
	var props := ClassDB.class_get_property_list(cls, true)
	print("  properties:%s" % ("" if _has_storage_props(props) else " (none)"))
	for p in props:
		if p.usage & (PROPERTY_USAGE_CATEGORY | PROPERTY_USAGE_GROUP | PROPERTY_USAGE_SUBGROUP):
			continue
		print("    %s: %s%s" % [p.name, _type_name(p), _hint_suffix(p)])
	var signals := ClassDB.class_get_signal_list(cls, true)
	print("  signals:%s" % ("" if not signals.is_empty() else " (none)"))
	for s in signals:
		var args := PackedStringArray()
		for a in s.args:
			args.append("%s: %s" % [a.name, _type_name(a)])
		print("    %s(%s)" % [s.name, ", ".join(args)])
	_report_warnings(cls)


func _report_warnings(cls: StringName) -> void:
	if not ClassDB.can_instantiate(cls):
		print("  configuration warnings: (not instantiable)")
		return
	var obj: Object = ClassDB.instantiate(cls)
	if obj == null:
		print("  configuration warnings: (instantiate() returned null)")
		return
	var warnings: Variant = null
	if obj.has_method(&"_get_configuration_warnings"):
		warnings = obj.call(&"_get_configuration_warnings")
	elif obj.has_method(&"get_configuration_warnings"):
		warnings = obj.call(&"get_configuration_warnings")
	if warnings == null:
		print("  configuration warnings: (not callable from a script)")
	elif warnings.is_empty():
		print("  configuration warnings of a new instance: (none)")
	else:
		print("  configuration warnings of a new instance:")
		for w in warnings:
			print("    - %s" % w)
	if not obj is RefCounted:
		obj.free()


static func _has_storage_props(props: Array[Dictionary]) -> bool:
	for p in props:
		if not p.usage & (PROPERTY_USAGE_CATEGORY | PROPERTY_USAGE_GROUP | PROPERTY_USAGE_SUBGROUP):
			return true
	return false


static func _type_name(p: Dictionary) -> String:
	if p.type == TYPE_OBJECT and not String(p.class_name).is_empty():
		return String(p.class_name)
	if p.type == TYPE_NIL:
		return "Variant"
	return type_string(p.type)


static func _hint_suffix(p: Dictionary) -> String:
	var hint_string := String(p.get("hint_string", ""))
	if hint_string.is_empty() or p.type == TYPE_OBJECT:
		return ""
	return "  [%s]" % hint_string
