class_name RoomProbeTestCase
extends RefCounted
## Base class of RoomProbe's GDScript tests.
##
## A test file is res://tests/test_*.gd (tests/godot/ in the repository); it extends
## RoomProbeTestCase and defines methods named test_*, run in the order they are written.
## A test may `await` (frames, signals); `tree` is the running SceneTree.
## Every test must assert something, call fail() or call skip(): a test that does none of
## these fails with "test asserted nothing". See tests/README.md.

## The SceneTree the tests run in. Add nodes under tree.root and free them in after_each().
var tree: SceneTree
## True when the run has a real renderer (the "rendering" suite, user argument --rendering).
var rendering := false
## Folder where tests may write artefacts (screenshots); empty when none was given.
var artifacts_dir := ""
## Seconds a single test may take before the runner gives up on it. Override in _init().
var timeout_s := 60.0

var _assertions := 0
var _failures: Array[String] = []
var _skip_reason := ""
var _skipped := false
var _expected_errors: Array[String] = []
var _expected_warnings: Array[String] = []
var _log_collector: Object = null  # the runner's ErrorCollector (take_logged)


## Called before every test. Override; may await.
func before_each() -> void:
	pass


## Called after every test, also after a failed one. Override; may await.
func after_each() -> void:
	pass


# --- assertions ---------------------------------------------------------------------------


func assert_true(cond: Variant, msg: String = "") -> bool:
	_assertions += 1
	if cond:
		return true
	_record_failure(_join(msg, "expected true, got %s" % _repr(cond)))
	return false


func assert_false(cond: Variant, msg: String = "") -> bool:
	_assertions += 1
	if not cond:
		return true
	_record_failure(_join(msg, "expected false, got %s" % _repr(cond)))
	return false


func assert_eq(actual: Variant, expected: Variant, msg: String = "") -> bool:
	_assertions += 1
	if _equal(actual, expected):
		return true
	_record_failure(_join(msg, "expected %s, got %s" % [_repr(expected), _repr(actual)]))
	return false


func assert_ne(actual: Variant, unexpected: Variant, msg: String = "") -> bool:
	_assertions += 1
	if not _equal(actual, unexpected):
		return true
	_record_failure(_join(msg, "expected a value other than %s" % _repr(unexpected)))
	return false


## Floats (and ints) within tol; Vector2/3/4, Color, Quaternion and float/int arrays
## componentwise within tol.
func assert_near(actual: Variant, expected: Variant, tol: float, msg: String = "") -> bool:
	_assertions += 1
	var a := _components(actual)
	var e := _components(expected)
	if a.is_empty() and not _is_empty_array(actual) or e.is_empty() and not _is_empty_array(expected):
		_record_failure(_join(msg, "assert_near cannot compare %s with %s" % [type_string(typeof(actual)), type_string(typeof(expected))]))
		return false
	if a.size() != e.size():
		_record_failure(_join(msg, "expected %s (%d components), got %s (%d components)" % [_repr(expected), e.size(), _repr(actual), a.size()]))
		return false
	for i in a.size():
		if is_nan(a[i]) or is_nan(e[i]) or absf(a[i] - e[i]) > tol:
			_record_failure(_join(msg, "expected %s within %s, got %s" % [_repr(expected), tol, _repr(actual)]))
			return false
	return true


func assert_null(value: Variant, msg: String = "") -> bool:
	_assertions += 1
	if value == null:
		return true
	_record_failure(_join(msg, "expected null, got %s" % _repr(value)))
	return false


func assert_not_null(value: Variant, msg: String = "") -> bool:
	_assertions += 1
	if value != null:
		return true
	_record_failure(_join(msg, "expected a value, got null"))
	return false


## Always fails the test with msg.
func fail(msg: String) -> void:
	_assertions += 1
	_record_failure(msg)


## Marks the test as skipped. Return right after it: `return skip("needs a renderer")`.
func skip(reason: String) -> void:
	_skipped = true
	_skip_reason = reason


## Declares that the current test will log an engine error whose text contains
## substring; the runner then neither fails the test nor prints the error as a failure.
## Each expected error must occur, or the test fails.
## Godot still prints the error line itself; the Python runner knows which ones were
## expected from the "[EXPECTED-ERROR]" lines the runner prints.
func expect_error(substring: String) -> void:
	_expected_errors.append(substring)


## Declares that the current test will log a warning whose text contains substring (a clamped
## property, say); the test fails if none is logged. Other warnings never fail a test.
func expect_warning(substring: String) -> void:
	_expected_warnings.append(substring)


## The engine errors and warnings logged since the test began or since the last call, as
## {"errors": [...], "warnings": [...]} (message texts), for a test that judges each message
## itself (a sweep over many properties). The errors taken count as expected: neither the
## runner nor tools/testrun/godot.py fails the test for them.
func take_logged() -> Dictionary:
	var errors: Array[String] = []
	for e in _log_collector.take():
		var details: String = e.get_slice("\t", 0)
		print("[EXPECTED-ERROR] %s" % details)
		errors.append(details)
	return {"errors": errors, "warnings": _log_collector.take_warnings()}


## Declares that an engine bug makes Godot report "count RIDs of type rid_type were leaked"
## at exit because of what this test did (e.g. "Texture"). tools/testrun/godot.py adds up these
## declarations and tolerates exactly that many such RIDs; any other count still fails.
## Name the engine issue in reason, and remove the call once the engine is fixed.
func known_engine_leak(count: int, rid_type: String, reason: String) -> void:
	print("[KNOWN-ENGINE-LEAK] %d %s: %s" % [count, rid_type, reason])


## An absolute path in the repository. godot_project/ is res://, so the repository is its parent,
## except for a scratch copy of the project elsewhere (the sanitizer runs of tools/testrun/sanitize.py
## copy it under build/), whose runner names the repository in $ROOMPROBE_REPO.
static func repo_path(relative: String) -> String:
	var repo := OS.get_environment("ROOMPROBE_REPO")
	if repo.is_empty():
		repo = ProjectSettings.globalize_path("res://").path_join("..")
	return repo.path_join(relative).simplify_path()


## Removes the folder p_path and everything in it; nothing when it is not there.
static func remove_folder(p_path: String) -> void:
	if not DirAccess.dir_exists_absolute(p_path):
		return
	for sub in DirAccess.get_directories_at(p_path):
		remove_folder(p_path.path_join(sub))
	for file in DirAccess.get_files_at(p_path):
		DirAccess.remove_absolute(p_path.path_join(file))
	DirAccess.remove_absolute(p_path)


## "thread" or "address" when the library under test is built with that sanitizer (the runner's
## --sanitize sets $ROOMPROBE_SANITIZER), else "". Its workers then run several times slower.
static func sanitizer() -> String:
	return OS.get_environment("ROOMPROBE_SANITIZER")


## The synthetic recording the runner renders before the Godot suites (1 s of living_room,
## build/bin/roomprobe_synth), as an absolute path.
func fixture_recording() -> String:
	return repo_path("build/test-data/living_room_1s")


## The same second with the fisheye bracketed (every other frame 5 stops shorter, each frame's
## exposure in its capture.txt), as an absolute path.
func fixture_bracketed_recording() -> String:
	return fixture_recording() + "_bracketed"


## The same second of the living room from the RGB-D camera alone (roomprobe_synth --no-fisheye:
## no fisheye stream), as an absolute path.
func fixture_rgbd_only_recording() -> String:
	return fixture_recording() + "_rgbd_only"


## False, and the test skipped, when the fixture recording (or p_path) is not there.
func need_fixture_recording(p_path: String = "") -> bool:
	var path := fixture_recording() if p_path.is_empty() else p_path
	if not FileAccess.file_exists(path.path_join("rgb.txt")):
		skip("no synthetic recording at %s (the runner makes it with build/bin/roomprobe_synth)" % path)
		return false
	return true


## A RigCapture named "Rig" on the fixture recording, stepped by hand (PACING_STEP, no
## autoplay), not yet in the tree.
func fixture_rig() -> Node:
	var rig = ClassDB.instantiate("RigCapture")
	rig.name = "Rig"
	rig.pacing = 1  # PACING_STEP
	rig.autoplay = false
	rig.recording_path = fixture_recording()
	return rig


## The ground-truth cubemap (an N x 6N EXR strip) of recording p_dir's last line, as six RGBF faces.
func ground_truth_faces(p_dir: String) -> Array[Image]:
	var lines := FileAccess.get_file_as_string(p_dir.path_join("groundtruth/cubemaps.txt")).strip_edges().split("\n")
	var last := lines[lines.size() - 1].split(" ")
	var strip := Image.load_from_file(p_dir.path_join(last[2]))
	strip.convert(Image.FORMAT_RGBF)
	var n := strip.get_width()
	var faces: Array[Image] = []
	for f in 6:
		faces.append(strip.get_region(Rect2i(0, f * n, n, n)))
	return faces


## PSNR in dB of six faces p_faces against p_truth (linear values clamped to [0, 1], peak 1).
static func cubemap_psnr(p_faces: Array, p_truth: Array[Image]) -> float:
	var se := 0.0
	var count := 0
	for f in 6:
		var a: Image = p_faces[f]
		var b: Image = p_truth[f]
		for y in b.get_height():
			for x in b.get_width():
				var ca := a.get_pixel(x, y)
				var cb := b.get_pixel(x, y)
				se += pow(clampf(ca.r, 0, 1) - clampf(cb.r, 0, 1), 2) + pow(clampf(ca.g, 0, 1) - clampf(cb.g, 0, 1), 2) + pow(clampf(ca.b, 0, 1) - clampf(cb.b, 0, 1), 2)
				count += 3
	return 10.0 * log(1.0 / maxf(se / count, 1e-12)) / log(10.0)


## Adds node under tree.root and returns it. Free it in after_each() (or in the test).
func add_to_tree(node: Node) -> Node:
	tree.root.add_child(node)
	return node


## The live pipeline around p_rig (a RigCapture, opened here): room, SLAM and probe, none given a
## NodePath, the room from the rig's floorplan, the probe at its first probe position. Returns
## {scene, rig, slam, room, probe}; the scene is in the tree: free it in after_each().
func live_scene(p_rig: Node) -> Dictionary:
	var scene := Node3D.new()
	p_rig.name = "Rig"
	scene.add_child(p_rig)
	var room = ClassDB.instantiate("CoarseRoomModel")
	room.name = "Room"
	room.texel_size = 0.05
	room.pose_source = 1  # POSE_SOURCE_DENSE_SLAM
	scene.add_child(room)
	var slam = ClassDB.instantiate("DenseSLAM")
	slam.name = "SLAM"
	scene.add_child(slam)
	var probe = ClassDB.instantiate("RoomProbe")
	probe.name = "Probe"
	probe.resolution = 32
	probe.update_mode = 1  # UPDATE_ALWAYS
	scene.add_child(probe)
	assert_true(p_rig.open(), p_rig.get_last_error())
	room.floorplan = p_rig.get_room_floorplan()
	room.ceiling_height = p_rig.get_room_ceiling_height()
	add_to_tree(scene)
	probe.global_position = p_rig.get_probe_positions()[0]
	return {"scene": scene, "rig": p_rig, "slam": slam, "room": room, "probe": probe}


## Waits (real time) until p_done returns true, at most p_seconds; false on time-out.
func wait_until(p_done: Callable, p_seconds: float) -> bool:
	var start := Time.get_ticks_msec()
	while not p_done.call():
		if Time.get_ticks_msec() - start > p_seconds * 1000.0:
			return false
		await tree.process_frame
	return true


## Waits n process frames.
func wait_frames(n: int) -> void:
	for i in n:
		await tree.process_frame


# --- runner interface (not for tests) ------------------------------------------------------


func _rp_reset() -> void:
	_assertions = 0
	_failures.clear()
	_skip_reason = ""
	_skipped = false
	_expected_errors.clear()
	_expected_warnings.clear()


func _record_failure(msg: String) -> void:
	var line := _caller_line()
	_failures.append(msg + (" (line %d)" % line if line > 0 else ""))


# First stack frame outside this file: the test's own line.
func _caller_line() -> int:
	var stack := get_stack()
	if stack.is_empty():
		return -1
	var me: String = stack[0].source  # this file (get_script() would name the test's file)
	for frame in stack:
		if frame.source != me:
			return frame.line
	return -1


static func _join(msg: String, detail: String) -> String:
	return detail if msg.is_empty() else "%s: %s" % [msg, detail]


static func _is_numeric(v: Variant) -> bool:
	return typeof(v) == TYPE_INT or typeof(v) == TYPE_FLOAT


static func _equal(a: Variant, b: Variant) -> bool:
	if typeof(a) != typeof(b) and not (_is_numeric(a) and _is_numeric(b)):
		# StringName and String compare equal in GDScript; keep that.
		if (typeof(a) == TYPE_STRING or typeof(a) == TYPE_STRING_NAME) and (typeof(b) == TYPE_STRING or typeof(b) == TYPE_STRING_NAME):
			return String(a) == String(b)
		return false
	return a == b


static func _is_empty_array(v: Variant) -> bool:
	return typeof(v) >= TYPE_ARRAY and typeof(v) != TYPE_DICTIONARY and v.is_empty()


static func _components(v: Variant) -> PackedFloat64Array:
	match typeof(v):
		TYPE_INT, TYPE_FLOAT:
			return PackedFloat64Array([float(v)])
		TYPE_VECTOR2, TYPE_VECTOR2I:
			return PackedFloat64Array([v.x, v.y])
		TYPE_VECTOR3, TYPE_VECTOR3I:
			return PackedFloat64Array([v.x, v.y, v.z])
		TYPE_VECTOR4, TYPE_VECTOR4I, TYPE_QUATERNION:
			return PackedFloat64Array([v.x, v.y, v.z, v.w])
		TYPE_COLOR:
			return PackedFloat64Array([v.r, v.g, v.b, v.a])
		TYPE_PACKED_FLOAT32_ARRAY, TYPE_PACKED_FLOAT64_ARRAY, TYPE_PACKED_INT32_ARRAY, TYPE_PACKED_INT64_ARRAY, TYPE_PACKED_BYTE_ARRAY:
			return PackedFloat64Array(Array(v))
		TYPE_PACKED_VECTOR2_ARRAY, TYPE_PACKED_VECTOR3_ARRAY, TYPE_PACKED_VECTOR4_ARRAY, TYPE_PACKED_COLOR_ARRAY, TYPE_ARRAY:
			var out := PackedFloat64Array()
			for item in v:
				var c := _components(item)
				if c.is_empty():
					return PackedFloat64Array()
				out.append_array(c)
			return out
	return PackedFloat64Array()


static func _repr(v: Variant) -> String:
	match typeof(v):
		TYPE_STRING:
			return '"%s"' % v
		TYPE_STRING_NAME:
			return '&"%s"' % v
		TYPE_NIL:
			return "null"
		TYPE_OBJECT:
			return str(v) if is_instance_valid(v) else "<freed object>"
	var s := str(v)
	return s if s.length() <= 200 else s.substr(0, 200) + "..."
