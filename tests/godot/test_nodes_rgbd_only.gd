extends RoomProbeTestCase
## Issue #43: a recording of an RGB-D camera alone (roomprobe_synth --no-fisheye: the same second of
## the living room as the fixture, without the fisheye stream) through the nodes, stepped, as a
## scene without code would play it: the coarse model is textured from the RGB camera's views, the
## probe's map shows the room, and no node asks for a fisheye.

var _scene: Node3D


func _init() -> void:
	timeout_s = 120.0


func after_each() -> void:
	if is_instance_valid(_scene):
		_scene.free()
	_scene = null


func test_an_rgbd_camera_alone_textures_the_room_and_the_probe_shows_it() -> void:
	var path := fixture_rgbd_only_recording()
	if not need_fixture_recording(path):
		return
	var rig = fixture_rig()
	rig.recording_path = path
	var s := live_scene(rig)
	_scene = s.scene
	s.room.pose_source = 0  # POSE_SOURCE_GROUND_TRUTH: the texture is what is judged, not tracking
	assert_eq(rig.get_frame_count(1), 0, "the recording has no fisheye stream")
	var updated := [0]
	s.room.texture_updated.connect(func(_view: int): updated[0] += 1)
	while rig.step():
		s.room.integrate_rig_frame()
	s.room.finish_inpainting()
	# One view at the first frame, then one every 1/12 s of the 1-s recording.
	assert_true(s.room.get_integrated_frame_count() >= 6, "views: %d" % s.room.get_integrated_frame_count())
	assert_eq(updated[0], s.room.get_integrated_frame_count(), "texture_updated once a view")
	assert_true(s.room.has_texture_data(), "the room is textured")
	var stats: Dictionary = s.room.get_last_frame_stats()
	assert_true(stats.texels_visible > 0, str(stats))
	# The map at the recording's probe against its true cubemap, and a black map against it.
	var truth := ground_truth_faces(path)
	s.probe.resolution = truth[0].get_width()
	assert_true(s.probe.update_now())
	var faces := []
	var black := []
	for f in 6:
		faces.append(s.probe.get_face_image(f))
		black.append(Image.create(truth[0].get_width(), truth[0].get_width(), false, Image.FORMAT_RGBF))
	var psnr := cubemap_psnr(faces, truth)
	var psnr_black := cubemap_psnr(black, truth)
	print("    RGB-D camera alone, 1 s: the map at the probe %.2f dB against the truth (a black map %.2f dB)" % [psnr, psnr_black])
	# The room's light is in the map: it halves the error of a black map at least (3 dB).
	assert_true(psnr > psnr_black + 3.0, "%.2f dB, black %.2f dB" % [psnr, psnr_black])
	for node in [rig, s.room, s.probe, s.slam]:
		for warning in node.get_warnings():
			assert_false(warning.to_lower().contains("fisheye"), "%s asks for a fisheye: %s" % [node.name, warning])
