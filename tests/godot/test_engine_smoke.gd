extends RoomProbeTestCase
## Checks on the engine itself that the test harness and the project layout depend on.


class ReadyProbe extends Node:
	var ready_calls := 0

	func _ready() -> void:
		ready_calls += 1


var _node: Node


func after_each() -> void:
	if is_instance_valid(_node):
		_node.free()
	_node = null


func test_engine_is_godot_4_4_or_newer() -> void:
	var v := Engine.get_version_info()
	assert_eq(v.major, 4, "major version")
	assert_true(v.minor >= 4, "minor version %d should be >= 4" % v.minor)


func test_project_is_roomprobe() -> void:
	assert_eq(ProjectSettings.get_setting("application/config/name"), "RoomProbe")
	assert_eq(ProjectSettings.get_setting("application/run/main_scene"), "res://demo_scenes/main.tscn")


func test_symlinked_folders_resolve() -> void:
	# godot_project/{demo_scenes,shaders,tests} are symlinks to folders at the repository root.
	for dir in ["res://demo_scenes", "res://addons/roomprobe/shaders", "res://tests", "res://tests/lib"]:
		assert_true(DirAccess.dir_exists_absolute(dir), "%s should exist" % dir)
	assert_true(FileAccess.file_exists("res://demo_scenes/main.tscn"), "main scene file")
	assert_true(FileAccess.file_exists("res://addons/roomprobe/shaders/README.md"), "shaders/README.md")
	assert_true(ResourceLoader.exists("res://demo_scenes/main.tscn"), "main scene resource")
	var scene := load("res://demo_scenes/main.tscn") as PackedScene
	assert_not_null(scene, "main scene loads through the symlink")


func test_global_class_of_test_case_is_registered() -> void:
	# The editor import registers class_name RoomProbeTestCase from res://tests/lib/ (a symlink).
	var found := false
	for c in ProjectSettings.get_global_class_list():
		if c["class"] == &"RoomProbeTestCase":
			found = true
			assert_eq(c["path"], "res://tests/lib/test_case.gd")
	assert_true(found, "RoomProbeTestCase in the global class list")


func test_node_in_tree_gets_ready() -> void:
	var probe := ReadyProbe.new()
	_node = probe
	add_to_tree(probe)
	assert_true(probe.is_inside_tree(), "inside the tree")
	assert_eq(probe.ready_calls, 1, "_ready runs once when added")


func test_await_frames_advances() -> void:
	var before := Engine.get_process_frames()
	await wait_frames(3)
	assert_true(Engine.get_process_frames() >= before + 3, "three frames went by")


func test_assertion_helpers() -> void:
	assert_near(0.1 + 0.2, 0.3, 1e-9)
	assert_near(Vector3(1, 2, 3), Vector3(1, 2, 3.0005), 1e-3)
	assert_near(Color(0.5, 0.5, 0.5), Color(0.5, 0.5, 0.501), 1e-2)
	assert_eq(1, 1.0, "int and float compare by value")
	assert_ne("1", 1, "String and int differ")
	assert_eq(&"name", "name", "StringName equals String")
	# Failures are recorded, not thrown: check the helpers report them, then clear them.
	var failures_before := _failures.size()
	assert_eq(1, 2)
	assert_near(Vector2(0, 0), Vector2(0, 1), 0.5)
	var recorded := _failures.slice(failures_before)
	_failures.resize(failures_before)
	assert_eq(recorded.size(), 2, "two deliberate failures recorded")
	if recorded.size() == 2:
		assert_true(recorded[0].contains("expected 1, got 2") or recorded[0].contains("expected 2, got 1"), recorded[0])
		assert_true(recorded[0].contains("(line "), "failure names the caller's line: " + recorded[0])


func test_expected_engine_error_is_tolerated() -> void:
	expect_error("roomprobe deliberate test error")
	push_error("roomprobe deliberate test error")
	assert_true(true)
