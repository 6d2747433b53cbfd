extends SceneTree
## RoomProbe's GDScript test runner.
##
##   godot --headless --path godot_project -s res://tests/run_tests.gd [-- ARGS]
##
## User arguments (after --):
##   --filter SUBSTRING   run only tests whose "file::test_name" contains SUBSTRING
##   --files GLOB         which files in res://tests/ to run (default test_*.gd)
##   --rendering          a real renderer is present: rendering tests run instead of skipping
##   --artifacts DIR      folder (absolute path) where tests may write images and other artefacts
##   --allow-empty        no selected test is not a failure (tools/run_tests.py, several suites)
##
## Prints one line per test, "[PASS] file::test", "[FAIL] file::test: message (line N)" or
## "[SKIP] file::test: reason", then "GODOT_TESTS <passed> passed, <failed> failed,
## <skipped> skipped" and quits with 0 when nothing failed, else 1.

const TESTS_DIR := "res://tests"
const TEST_CASE_SCRIPT := "res://tests/lib/test_case.gd"


## Collects engine errors logged while a test runs (Godot >= 4.5).
class ErrorCollector extends Logger:
	var _mutex := Mutex.new()
	var _errors: Array[String] = []
	var _warnings: Array[String] = []
	## Script errors logged so far (a test stopped by one never completes its coroutine).
	var script_errors := 0

	func _log_error(function: String, file: String, line: int, code: String, rationale: String, _editor_notify: bool, error_type: int, script_backtraces: Array[ScriptBacktrace]) -> void:
		var details := rationale if not rationale.is_empty() else code
		if error_type == ERROR_TYPE_WARNING:
			# Warnings never fail a test; the ones a test expects (expect_warning) must occur.
			_mutex.lock()
			_warnings.append(details)
			_mutex.unlock()
			return
		var where := "%s:%d" % [file, line]
		# For errors raised from a script (push_error, failed engine calls) name the script line.
		for bt in script_backtraces:
			if bt != null and bt.get_frame_count() > 0:
				where = "%s:%d" % [bt.get_frame_file(0), bt.get_frame_line(0)]
				break
		_mutex.lock()
		if error_type == ERROR_TYPE_SCRIPT:
			script_errors += 1
		_errors.append("%s\t%s in %s" % [details, function, where])
		_mutex.unlock()

	func _log_message(_message: String, _error: bool) -> void:
		pass

	func take() -> Array[String]:
		_mutex.lock()
		var out := _errors.duplicate()
		_errors.clear()
		_mutex.unlock()
		return out

	func take_warnings() -> Array[String]:
		_mutex.lock()
		var out := _warnings.duplicate()
		_warnings.clear()
		_mutex.unlock()
		return out


var _passed := 0
var _failed := 0
var _skipped := 0
var _filter := ""
var _files_glob := "test_*.gd"
var _rendering := false
var _artifacts := ""
var _allow_empty := false
var _collector: ErrorCollector
var _orphans_reported := 0  # orphan nodes already blamed on single tests
# Watchdog: when the runner itself stops (a script error in this file or in test_case.gd
# ends its coroutine), _process() reports it and quits instead of leaving Godot running.
var _deadline_msec := 0
var _done := false


func _initialize() -> void:
	_parse_args(OS.get_cmdline_user_args())
	_collector = ErrorCollector.new()
	OS.add_logger(_collector)
	_deadline_msec = Time.get_ticks_msec() + 60_000
	_run_all()


func _process(_delta: float) -> bool:
	if not _done and Time.get_ticks_msec() > _deadline_msec:
		_done = true
		_report_fail("run_tests.gd::<runner>", "the runner made no progress; a script error in the harness?")
		_finish()
	return false


func _parse_args(args: PackedStringArray) -> void:
	var i := 0
	while i < args.size():
		var a := args[i]
		var has_value := i + 1 < args.size()
		if a == "--filter" and has_value:
			i += 1
			_filter = args[i]
		elif a.begins_with("--filter="):
			_filter = a.trim_prefix("--filter=")
		elif a == "--files" and has_value:
			i += 1
			_files_glob = args[i]
		elif a.begins_with("--files="):
			_files_glob = a.trim_prefix("--files=")
		elif a == "--artifacts" and has_value:
			i += 1
			_artifacts = args[i]
		elif a.begins_with("--artifacts="):
			_artifacts = a.trim_prefix("--artifacts=")
		elif a == "--rendering":
			_rendering = true
		elif a == "--allow-empty":
			_allow_empty = true
		else:
			printerr("run_tests.gd: ignoring unknown argument '%s'" % a)
		i += 1
	# A renderer only counts when there is one: --rendering with --headless renders nothing.
	_rendering = _rendering and DisplayServer.get_name() != "headless"


func _run_all() -> void:
	# Start on a frame boundary so that nodes added by tests get a full frame.
	await process_frame
	var files := _discover()
	var ran_any := false
	for file in files:
		if await _run_file(file):
			ran_any = true
	if not ran_any and not _allow_empty:
		var why := "no test matched --filter '%s'" % _filter if not _filter.is_empty() else "no tests in %s/%s" % [TESTS_DIR, _files_glob]
		_report_fail("run_tests.gd::discover", why)
	if _done:
		return
	_done = true
	# Let queue_free()d nodes go before the leak checks at exit.
	await process_frame
	_finish()


func _finish() -> void:
	if _collector != null:
		OS.remove_logger(_collector)
		_collector = null
	print("GODOT_TESTS %d passed, %d failed, %d skipped" % [_passed, _failed, _skipped])
	# quit() takes effect at the end of this frame.
	quit(0 if _failed == 0 else 1)


func _discover() -> PackedStringArray:
	var out := PackedStringArray()
	if not DirAccess.dir_exists_absolute(TESTS_DIR):
		return out
	for f in DirAccess.get_files_at(TESTS_DIR):
		if f.match(_files_glob) and f.ends_with(".gd"):
			out.append(f)
	out.sort()
	return out


# Runs the tests of one file; returns whether any test was selected.
func _run_file(file: String) -> bool:
	var path := TESTS_DIR.path_join(file)
	var script: Script = load(path)
	if script == null or not script.can_instantiate():
		if _selected(file + "::"):
			_report_fail("%s::<load>" % file, "the script does not load (parse error?)")
			return true
		return false
	var names := PackedStringArray()
	for m in script.get_script_method_list():
		var n: String = m.name
		if n.begins_with("test_") and not names.has(n) and _selected("%s::%s" % [file, n]):
			names.append(n)
	if names.is_empty():
		return false
	var orphans_before := Performance.get_monitor(Performance.OBJECT_ORPHAN_NODE_COUNT)
	var reported_before := _orphans_reported
	var inst: Object = script.new()
	if not inst is RoomProbeTestCase:
		_report_fail("%s::<load>" % file, "the script does not extend RoomProbeTestCase (%s)" % TEST_CASE_SCRIPT)
		if not inst is RefCounted:
			inst.free()
		return true
	var tc: RoomProbeTestCase = inst
	inst = null
	_deadline_msec = Time.get_ticks_msec() + 60_000
	tc.tree = self
	tc.rendering = _rendering
	tc.artifacts_dir = _artifacts
	tc._log_collector = _collector
	for n in names:
		await _run_test(tc, file, n)
	tc.tree = null
	tc._log_collector = null
	tc = null  # the last reference: the test case (and what its members hold) goes now
	await process_frame
	var orphans := int(Performance.get_monitor(Performance.OBJECT_ORPHAN_NODE_COUNT) - orphans_before) - (_orphans_reported - reported_before)
	if orphans > 0:
		_report_fail("%s::<file>" % file, "leaked %d orphan node(s) held by the test case and never freed (free them in after_each)" % orphans)
	return true


# Whether the test "file::name" passes --filter. (String.contains("") is false in Godot.)
func _selected(id: String) -> bool:
	return _filter.is_empty() or id.contains(_filter)


func _run_test(tc: RoomProbeTestCase, file: String, test_name: String) -> void:
	var id := "%s::%s" % [file, test_name]
	# Under the Mobile renderer every id says so: the rendering suite runs the same tests under both.
	if _rendering and RenderingServer.get_current_rendering_method() == "mobile":
		id += "@mobile"
	tc._rp_reset()
	_collector.take()
	_collector.take_warnings()
	# Before, the test and after each get timeout_s; then some slack.
	_deadline_msec = Time.get_ticks_msec() + int(tc.timeout_s * 3000.0) + 30_000
	var orphans_before := Performance.get_monitor(Performance.OBJECT_ORPHAN_NODE_COUNT)

	var finished := await _call_with_timeout(tc, "before_each", tc.timeout_s)
	var ran_test := false
	if not finished:
		tc._failures.append("before_each did not finish within %s s" % tc.timeout_s)
	elif tc._failures.is_empty() and not tc._skipped:
		ran_test = true
		if not await _call_with_timeout(tc, test_name, tc.timeout_s):
			tc._failures.append("did not finish within %s s (timeout_s)" % tc.timeout_s)
	if not await _call_with_timeout(tc, "after_each", tc.timeout_s):
		tc._failures.append("after_each did not finish within %s s" % tc.timeout_s)
	# queue_free()d nodes are deleted at the end of the frame.
	await process_frame

	var problems: Array[String] = []
	problems.append_array(tc._failures)
	var expected := tc._expected_errors.duplicate()
	for e in _collector.take():
		var details: String = e.get_slice("\t", 0)
		var matched := -1
		for i in expected.size():
			if details.contains(expected[i]):
				matched = i
				break
		if matched >= 0:
			expected.remove_at(matched)
			print("[EXPECTED-ERROR] %s" % details)
		else:
			problems.append("engine error: %s" % e.replace("\t", " (") + ")")
	for e in expected:
		problems.append("expected an error containing \"%s\", none was logged" % e)
	var warnings := _collector.take_warnings()
	for w in tc._expected_warnings:
		if not warnings.any(func(logged: String) -> bool: return logged.contains(w)):
			problems.append("expected a warning containing \"%s\", none was logged" % w)
	var orphans := int(Performance.get_monitor(Performance.OBJECT_ORPHAN_NODE_COUNT) - orphans_before)
	if orphans > 0:
		_orphans_reported += orphans
		problems.append("leaked %d orphan node(s) (nodes not in the tree and never freed)" % orphans)

	if not problems.is_empty():
		_report_fail(id, " | ".join(problems))
	elif tc._skipped:
		_skipped += 1
		print("[SKIP] %s: %s" % [id, tc._skip_reason])
	elif ran_test and tc._assertions == 0:
		_report_fail(id, "test asserted nothing")
	else:
		_passed += 1
		print("[PASS] %s" % id)


func _report_fail(id: String, message: String) -> void:
	_failed += 1
	print("[FAIL] %s: %s" % [id, message])


# Calls tc.method(), awaiting it when it is a coroutine; false when it did not finish in time
# or stopped on a script error after an await (its coroutine then never completes).
func _call_with_timeout(tc: RoomProbeTestCase, method: String, timeout_s: float) -> bool:
	var script_errors_before := _collector.script_errors
	var result: Variant = tc.call(method)
	# A coroutine returns its GDScriptFunctionState (not a type scripts can name). That state
	# goes invalid as soon as the function resumes, yet still emits "completed" when the
	# function returns after further awaits: wait for the signal, not for is_valid().
	if not (result is Object and is_instance_valid(result) and result.get_class() == "GDScriptFunctionState"):
		return true
	var state := {"done": false}
	var on_done := func(_value: Variant = null) -> void: state.done = true
	(result as Object).connect("completed", on_done)
	var deadline := Time.get_ticks_msec() + int(timeout_s * 1000.0)
	while not state.done and Time.get_ticks_msec() < deadline and _collector.script_errors == script_errors_before:
		await process_frame
	return state.done
