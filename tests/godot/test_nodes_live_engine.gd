extends RoomProbeTestCase
## The live engine in real time (#9): RigCapture plays the fixture recording on its capture thread,
## the engine's workers track, texture and render, and the nodes only copy results on the main
## thread. Wired with no NodePaths at all: each node finds its collaborator in the scene.

var _scene: Node3D


func _init() -> void:
	timeout_s = 180.0


func after_each() -> void:
	Engine.time_scale = 1.0
	if is_instance_valid(_scene):
		_scene.free()
	_scene = null


## Rig (real time), SLAM, room and probe, none of them given a NodePath.
func _scene_without_paths() -> Dictionary:
	var rig = fixture_rig()
	rig.pacing = 0  # PACING_REAL_TIME
	var s := live_scene(rig)
	_scene = s.scene
	return s


func test_plays_in_real_time_off_the_main_thread() -> void:
	if not need_fixture_recording():
		return
	var s := _scene_without_paths()
	var maps := [0]
	s.probe.environment_map_updated.connect(func(): maps[0] += 1)
	if not sanitizer().is_empty():
		# Instrumented workers are several times slower (TSan: the first pose came after the
		# recording's last fisheye frame): the scene's clock, which paces the recording, runs
		# ten times slower, so that they keep up as in a plain build.
		Engine.time_scale = 0.1
	s.rig.play()
	# The 1-s recording plays by the scene's clock; the workers keep up or drop frames.
	assert_true(await wait_until(func(): return not s.rig.is_playing(), 30.0), "the recording played to its end")
	s.room.finish_inpainting()
	assert_true(await wait_until(func(): return s.slam.get_processed_frame_count() > 0 and maps[0] > 0, 10.0), "results reached the nodes")
	assert_eq(s.slam.get_warnings().size(), 0, str(s.slam.get_warnings()))
	assert_eq(s.room.get_warnings().size(), 0, str(s.room.get_warnings()))
	assert_eq(Array(s.probe.get_warnings()).filter(func(w): return not w.contains("reaches nothing")).size(), 0, str(s.probe.get_warnings()))
	var stats: Dictionary = s.slam.get_stats()
	assert_true(stats.integrated_frames > 0, str(stats))
	# Every frame the engine took was tracked well on this sequence (the step-mode test checks the pose to 1 cm).
	assert_eq(s.slam.get_tracking_state(), 1, s.slam.get_tracking_reason())
	assert_true(s.room.get_integrated_frame_count() > 0, "fisheye frames were posed by the SLAM worker's trajectory")
	assert_not_null(s.probe.get_cubemap())
	assert_not_null(s.slam.get_camera_image_texture(), "the AR background is the tracked frame's image")


func test_freeing_the_slam_node_mid_run_is_clean() -> void:
	await _free_mid_run("SLAM")


func test_freeing_the_room_node_mid_run_is_clean() -> void:
	await _free_mid_run("Room")


func test_freeing_the_probe_node_mid_run_is_clean() -> void:
	await _free_mid_run("Probe")


func test_freeing_the_capture_node_mid_run_is_clean() -> void:
	await _free_mid_run("Rig")


## Frees one node while the workers are busy; the others go on, and nothing is logged (the
## runner fails a test on any engine error or leak).
func _free_mid_run(p_victim: String) -> void:
	if not need_fixture_recording():
		return
	_scene_without_paths()
	_scene.get_node("Rig").play()
	await wait_frames(5)
	_scene.get_node(p_victim).free()
	await wait_frames(5)
	assert_false(_scene.has_node(p_victim))


func test_stopping_while_busy_is_prompt() -> void:
	if not need_fixture_recording():
		return
	var s := _scene_without_paths()
	s.rig.play()
	await wait_frames(3)
	# stop() joins the capture thread and the engine's workers, each within about one stage.
	var start := Time.get_ticks_usec()
	s.rig.stop()
	var stop_ms := (Time.get_ticks_usec() - start) / 1000.0
	assert_true(stop_ms < 2000.0, "stop() returned in %.1f ms" % stop_ms)
	assert_false(s.rig.is_playing())
