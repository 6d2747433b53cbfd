extends RoomProbeTestCase
## demo_scenes/no_code.tscn, a scene with no script (issue #15): RigCapture, CoarseRoomModel
## (its floorplan from the recording), DenseSLAM (driving the AR camera, its field of view and
## the camera-image background) and a chrome StandardMaterial3D sphere under a SurfaceAnchor,
## whose RoomProbe feeds the WorldEnvironment's sky. Only the recording path is set here; the recording plays in real time
## through the engine's threads. Rendered: the background is the camera image, and
## the sphere, where the AR camera sees it, is neither the image behind it nor black.

const SIZE := Vector2i(160, 120)

var _viewport: SubViewport


func after_each() -> void:
	if is_instance_valid(_viewport):
		_viewport.free()
	_viewport = null


func test_a_scene_with_no_script_shows_a_reflecting_sphere_over_the_camera_image() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	if not need_fixture_recording():
		return
	var scene: Node3D = load("res://demo_scenes/no_code.tscn").instantiate()
	scene.get_node("Rig").recording_path = fixture_recording()
	await _play_and_check(scene, "no_code_scene.png")


## Issue #43: the same scene on a recording of an RGB-D camera alone (no fisheye stream): the coarse
## model is textured from the RGB camera, and the sphere reflects the room all the same.
func test_the_scene_plays_a_recording_of_an_rgbd_camera_alone() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	if not need_fixture_recording(fixture_rgbd_only_recording()):
		return
	var scene: Node3D = load("res://demo_scenes/no_code.tscn").instantiate()
	scene.get_node("Rig").recording_path = fixture_rgbd_only_recording()
	await _play_and_check(scene, "no_code_scene_rgbd_only.png")
	assert_true(scene.get_node("Room").has_texture_data(), "the room is textured from the RGB camera")


## Issue #40: the same scene with dense SLAM and the maps' filtering on Vulkan compute (lavapipe here), in
## the same process as Godot's own Vulkan renderer: it renders as on the CPU, and RigCapture has
## no warning that the kernels fell back to the CPU.
func test_the_scene_with_the_vulkan_compute_backend_renders_without_falling_back() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	if not need_fixture_recording():
		return
	var scene: Node3D = load("res://demo_scenes/no_code.tscn").instantiate()
	var rig = scene.get_node("Rig")
	rig.recording_path = fixture_recording()
	rig.compute_backend = 1  # COMPUTE_BACKEND_VULKAN
	await _play_and_check(scene, "no_code_scene_vulkan.png")
	for warning in rig.get_warnings():
		assert_false(warning.contains("compute_backend"), "tracking, fusion, raycasts, SH and the GGX prefilter stayed on the Vulkan device: %s" % warning)


## Issue #37: README's quick start, followed literally, gave a grey screen. The scene built here
## from its step 2 alone: the nodes it names, no NodePath between them, and only the settings it
## names (the recording, the room from the recording, the probe's world_environment and Always).
func test_the_quick_start_as_written_reflects_the_room() -> void:
	if not rendering:
		return skip("needs a renderer (rendering suite: --rendering under a display)")
	if not need_fixture_recording():
		return
	var scene := Node3D.new()
	var rig = ClassDB.instantiate("RigCapture")
	rig.name = "Rig"
	rig.recording_path = fixture_recording()
	scene.add_child(rig)
	var slam = ClassDB.instantiate("DenseSLAM")
	slam.name = "SLAM"
	scene.add_child(slam)
	var room = ClassDB.instantiate("CoarseRoomModel")
	room.name = "Room"
	room.floorplan_source = 1  # FLOORPLAN_RECORDING
	scene.add_child(room)
	var camera := Camera3D.new()
	camera.name = "Camera3D"
	scene.add_child(camera)
	var world := WorldEnvironment.new()
	world.name = "WorldEnvironment"
	scene.add_child(world)
	var anchor = ClassDB.instantiate("SurfaceAnchor")
	anchor.name = "OnTheTable"
	anchor.position = Vector3(2.5, 0.75, 2.0)  # where the user drops it: over the recording's table
	scene.add_child(anchor)
	var ball := MeshInstance3D.new()  # the user's object: a chrome sphere
	ball.name = "ChromeBall"
	var sphere := SphereMesh.new()
	sphere.radius = 0.1
	sphere.height = 0.2
	ball.mesh = sphere
	var chrome := StandardMaterial3D.new()
	chrome.metallic = 1.0
	chrome.roughness = 0.05
	ball.material_override = chrome
	ball.position = Vector3(0, 0.1, 0)
	anchor.add_child(ball)
	var probe = ClassDB.instantiate("RoomProbe")
	probe.name = "Probe"
	probe.update_mode = 1  # UPDATE_ALWAYS
	ball.add_child(probe)
	probe.world_environment = NodePath("../../../WorldEnvironment")  # the one probe setting README names
	await _play_and_check(scene, "quick_start_scene.png")
	assert_eq(probe.get_warnings(), PackedStringArray(), "the probe is content")
	assert_eq(slam.get_warnings(), PackedStringArray(), "DenseSLAM is content")


## Plays p_scene's recording in real time in a viewport, then checks the picture: the background
## is the camera image, and the sphere (OnTheTable/ChromeBall) reflects the room over it.
func _play_and_check(scene: Node3D, p_picture: String) -> void:
	_viewport = SubViewport.new()
	_viewport.size = SIZE
	_viewport.own_world_3d = true
	_viewport.render_target_update_mode = SubViewport.UPDATE_ALWAYS
	_viewport.add_child(scene)
	add_to_tree(_viewport)
	var slam = scene.get_node("SLAM")
	var camera: Camera3D = scene.get_node("Camera3D")
	assert_true(camera.is_current(), "the scene's camera is the one shown")
	var finished := [false]
	scene.get_node("Rig").finished.connect(func(): finished[0] = true)
	var start := Time.get_ticks_msec()
	# The 1-s recording in real time: SLAM takes what it can follow (under lavapipe and the test
	# runner, a few frames), then the rig finishes and the view stands still.
	while not finished[0] and Time.get_ticks_msec() - start < 10000:
		await tree.process_frame
	var last := -1
	while slam.get_processed_frame_count() != last and Time.get_ticks_msec() - start < 15000:
		last = slam.get_processed_frame_count()
		await wait_frames(5)
	assert_true(slam.get_processed_frame_count() >= 3, "SLAM took frames: %d" % slam.get_processed_frame_count())
	await wait_frames(3)
	assert_eq(scene.get_node("Room").floorplan, scene.get_node("Rig").get_room_floorplan(), "the room is the recording's")
	assert_near(camera.fov, scene.get_node("Rig").get_rgb_camera_fov(), 1e-3, "the AR camera's fov is the rig's")
	var shot := _viewport.get_texture().get_image()
	var video: Image = slam.get_camera_image_texture().get_image()
	if not artifacts_dir.is_empty():
		shot.save_png(artifacts_dir.path_join(p_picture))
	# The background: the camera image, stretched to the viewport. Compared at a grid of points;
	# a point on a sharp edge (the checkered wall) may fall on the other side of it in the other
	# image, so most, not all, must agree (8-bit both ways, bilinear: a few codes).
	var agree := 0
	var points := 0
	for gy in 6:
		for gx in 8:
			var p := Vector2i(int((gx + 0.5) * SIZE.x / 8), int((gy + 0.5) * SIZE.y / 6))
			var ours := shot.get_pixelv(p)
			var theirs := video.get_pixel(int((p.x + 0.5) * video.get_width() / SIZE.x), int((p.y + 0.5) * video.get_height() / SIZE.y))
			points += 1
			if Vector3(ours.r - theirs.r, ours.g - theirs.g, ours.b - theirs.b).length() < 0.08:
				agree += 1
	print("    no-code scene: %d of %d background points agree with the camera image" % [agree, points])
	# The sphere covers a few of the 48 points; a flipped or offset image agrees at almost none.
	assert_true(agree >= int(0.75 * points), "the background is the camera image (%d of %d points agree)" % [agree, points])
	# The sphere, where the AR camera sees its centre.
	var ball: Node3D = scene.get_node("OnTheTable/ChromeBall")
	assert_false(camera.is_position_behind(ball.global_position), "the sphere is in front of the camera")
	var at := camera.unproject_position(ball.global_position) * Vector2(SIZE) / Vector2(_viewport.get_visible_rect().size)
	var pixel := Vector2i(clampi(int(at.x), 0, SIZE.x - 1), clampi(int(at.y), 0, SIZE.y - 1))
	var ours := shot.get_pixelv(pixel)
	var behind := video.get_pixel(int((pixel.x + 0.5) * video.get_width() / SIZE.x), int((pixel.y + 0.5) * video.get_height() / SIZE.y))
	assert_true(ours.get_luminance() > 0.03, "the sphere reflects the room, not black (%s at %s)" % [ours, pixel])
	assert_true(Vector3(ours.r - behind.r, ours.g - behind.g, ours.b - behind.b).length() > 0.05,
			"the sphere covers the image behind it (%s against %s at %s)" % [ours, behind, pixel])
