@tool
extends EditorPlugin
## The editor suite's round trip (tools/testrun/editor.py, editor::scene-roundtrip): opens the scene,
## waits while its RoomProbe renders and drives the material, ReflectionProbe and sky, counts the
## maps it makes while nothing changes (none) and after a move (some), saves the scene as a user
## would, switches tabs, reloads and closes it, then quits. The runner compares the saved file
## with the original and fails on any error in the log.

const SCENE := "res://roundtrip_probe.tscn"


func _enter_tree() -> void:
	_run.call_deferred()


func _run() -> void:
	# Let the editor finish starting (it restores its layout and last scene tabs) first.
	for i in 100:
		await get_tree().process_frame
	EditorInterface.open_scene_from_path(SCENE)
	var root: Node
	for i in 300:
		await get_tree().process_frame
		root = EditorInterface.get_edited_scene_root()
		if root != null and root.scene_file_path == SCENE and root.is_inside_tree():
			break
	if root == null or root.scene_file_path != SCENE:
		print("roundtrip: the editor did not open %s" % SCENE)
		get_tree().quit(1)
		return
	var probe := root.get_node("Ball/Probe")
	for i in 60:
		await get_tree().process_frame
		if probe.get_cubemap() != null:
			break
	await _check_affordances(root, probe)
	var material: ShaderMaterial = probe.target_material
	if probe.get_cubemap() != null and material.get_shader_parameter("environment") == probe.get_cubemap():
		print("roundtrip: the probe made a map and drives its outputs")
	# Idle: nothing changes, so the probe (update_mode Always) renders nothing more.
	var maps := [0]
	probe.environment_map_updated.connect(func(): maps[0] += 1)
	for i in 60:
		await get_tree().process_frame
	print("roundtrip: idle maps %d in 60 frames" % maps[0])
	# Idle CPU: this process's CPU time over 3 s with the scene open, then with an empty scene.
	var scene_cpu := await _idle_cpu_percent(3.0)
	EditorInterface.open_scene_from_path("res://roundtrip_empty.tscn")
	var empty_cpu := await _idle_cpu_percent(3.0)
	EditorInterface.open_scene_from_path(SCENE)
	for i in 10:
		await get_tree().process_frame
	print("roundtrip: idle cpu scene %.1f%% empty %.1f%%" % [scene_cpu, empty_cpu])
	# A move is a change: one new map.
	var at: Vector3 = probe.position
	probe.position = at + Vector3(0.1, 0, 0)
	for i in 5:
		await get_tree().process_frame
	print("roundtrip: maps after a move %d" % maps[0])
	probe.position = at
	var error := EditorInterface.save_scene()
	print("roundtrip: saved %s (%s)" % [root.scene_file_path, error_string(error)])
	# After saving, the probe drives them again.
	if material.get_shader_parameter("environment") == probe.get_cubemap():
		print("roundtrip: driven again after saving")
	# Tab switches, a reload and closing: none may log an error (the runner reads the log).
	for path in ["res://roundtrip_empty.tscn", SCENE, "res://roundtrip_empty.tscn", SCENE]:
		EditorInterface.open_scene_from_path(path)
		for i in 20:
			await get_tree().process_frame
	EditorInterface.reload_scene_from_path(SCENE)
	for i in 20:
		await get_tree().process_frame
	EditorInterface.close_scene()
	for i in 20:
		await get_tree().process_frame
	print("roundtrip: switched tabs, reloaded and closed")
	get_tree().quit()


# The gizmos and the inspector's preview (addons/roomprobe): loaded, drawn, and the corner drag's
# geometry and undo work.
func _check_affordances(root: Node, probe: Node) -> void:
	var room: Node3D = root.get_node("Room")
	EditorInterface.edit_node(probe)
	for i in 10:
		await get_tree().process_frame
	var preview := EditorInterface.get_inspector().find_child("RoomProbeCubemapPreview", true, false)
	var cross: TextureRect = preview.get_node("Cross") if preview else null
	if cross and cross.texture and cross.texture.get_width() == 4 * probe.resolution:
		print("roundtrip: the inspector previews the map")
	if probe.get_gizmos().size() > 0 and room.get_gizmos().size() > 0:
		print("roundtrip: gizmos on the probe and the room")
	var gizmo_script := load("res://addons/roomprobe/floorplan_gizmo.gd")
	var hit = gizmo_script.floor_point(room, Vector3(1.5, 5.0, 2.0), Vector3(0.0, -1.0, 0.0))
	var before: PackedVector2Array = room.floorplan
	gizmo_script.move_corner(room, 2, Vector2(4.5, 3.5))
	var moved: bool = room.floorplan[2] == Vector2(4.5, 3.5) and room.is_valid()
	var undo := EditorInterface.get_editor_undo_redo()
	undo.create_action("test corner")
	undo.add_do_property(room, "floorplan", room.floorplan)
	undo.add_undo_property(room, "floorplan", before)
	undo.commit_action(false)
	undo.get_history_undo_redo(undo.get_object_history_id(room)).undo()
	if hit == Vector2(1.5, 2.0) and moved and room.floorplan == before:
		print("roundtrip: a corner moves on the floor and back")
	# The probe renders the restored room once; the idle count starts after that.
	for i in 30:
		await get_tree().process_frame


# The editor process's CPU time (all threads) over p_seconds of wall time, as a percentage of one
# core: utime + stime from /proc/self/stat, in clock ticks of 1/100 s (Linux's USER_HZ).
func _idle_cpu_percent(p_seconds: float) -> float:
	for i in 10:
		await get_tree().process_frame  # let the tab switch settle first
	var start_cpu := _cpu_ticks()
	var start := Time.get_ticks_usec()
	while Time.get_ticks_usec() - start < p_seconds * 1e6:
		await get_tree().process_frame
	var wall_s := (Time.get_ticks_usec() - start) / 1e6
	return (_cpu_ticks() - start_cpu) / 100.0 / wall_s * 100.0


func _cpu_ticks() -> int:
	# (/proc files report a length of 0: read the line, not the "whole file".)
	var file := FileAccess.open("/proc/self/stat", FileAccess.READ)
	var stat := file.get_line() if file else ""
	var fields := stat.substr(stat.rfind(")") + 2).split(" ")  # from field 3 (state) on
	return int(fields[11]) + int(fields[12])  # fields 14 and 15: utime, stime
