extends RoomProbeTestCase
## The coarse model live in Godot (paper §4.3-§4.7): a RigCapture steps through the synthetic
## living-room recording (1 s, rendered by the test runner), CoarseRoomModel textures the room
## from every fisheye frame (ground-truth poses), and a RoomProbe at the recording's probe renders
## the environment map, which is compared with the recording's ground-truth cubemap there.

var _dir := ""
var _scene: Node3D


func _init() -> void:
	_dir = fixture_recording()
	timeout_s = 120.0


func after_each() -> void:
	if is_instance_valid(_scene):
		_scene.free()
	_scene = null


## rig, room and probe, wired; the room takes the recording's floorplan.
func _make_scene() -> Array:
	_scene = Node3D.new()
	var rig = fixture_rig()
	_scene.add_child(rig)
	var room = ClassDB.instantiate("CoarseRoomModel")
	room.name = "Room"
	room.texel_size = 0.04
	room.pose_source = 0  # POSE_SOURCE_GROUND_TRUTH: the coarse model alone, no tracking
	_scene.add_child(room)
	var probe = ClassDB.instantiate("RoomProbe")
	probe.name = "Probe"
	_scene.add_child(probe)
	add_to_tree(_scene)
	assert_true(rig.open(), "the recording opens: %s" % rig.get_last_error())
	room.floorplan = rig.get_room_floorplan()
	room.ceiling_height = rig.get_room_ceiling_height()
	room.rig_capture = NodePath("../Rig")
	probe.position = rig.get_probe_positions()[0]
	probe.coarse_model = NodePath("../Room")
	return [rig, room, probe]


## Normalised cross-correlation of the luminance (clamped to [0, 1]) of p_faces and p_truth over
## the texels of the faces in p_face_list: 1 for a map with the truth's structure at any gain and offset, 0 for a map without
## any (a constant map, or noise).
static func _correlation(p_faces: Array, p_truth: Array[Image], p_face_list: Array) -> float:
	var a_values := PackedFloat32Array()
	var b_values := PackedFloat32Array()
	for f in p_face_list:
		var a: Image = p_faces[f]
		var b: Image = p_truth[f]
		for y in b.get_height():
			for x in b.get_width():
				var ca := a.get_pixel(x, y)
				var cb := b.get_pixel(x, y)
				a_values.append(Color(clampf(ca.r, 0, 1), clampf(ca.g, 0, 1), clampf(ca.b, 0, 1)).get_luminance())
				b_values.append(Color(clampf(cb.r, 0, 1), clampf(cb.g, 0, 1), clampf(cb.b, 0, 1)).get_luminance())
	var n := a_values.size()
	var ma := 0.0
	var mb := 0.0
	for i in n:
		ma += a_values[i]
		mb += b_values[i]
	ma /= n
	mb /= n
	var sab := 0.0
	var saa := 0.0
	var sbb := 0.0
	for i in n:
		sab += (a_values[i] - ma) * (b_values[i] - mb)
		saa += (a_values[i] - ma) * (a_values[i] - ma)
		sbb += (b_values[i] - mb) * (b_values[i] - mb)
	return sab / sqrt(maxf(saa * sbb, 1e-20))


func test_fisheye_frames_texture_the_room_and_the_ceiling_matches_the_truth() -> void:
	if not need_fixture_recording():
		return
	var parts := _make_scene()
	var rig = parts[0]
	var room = parts[1]
	var probe = parts[2]
	assert_true(rig.has_ground_truth())
	assert_false(room.has_texture_data(), "no texture before the first frame")
	var integrated := 0
	var updated := []
	room.texture_updated.connect(func(i: int): updated.append(i))
	while rig.step():
		if room.integrate_rig_frame():
			integrated += 1
			var stats: Dictionary = room.get_last_frame_stats()
			assert_true(stats.texels_updated <= stats.texels_visible)
		assert_false(room.integrate_rig_frame(), "a frame goes through once")
	assert_eq(integrated, rig.get_frame_count(1), "every fisheye frame went through")
	assert_eq(room.get_integrated_frame_count(), integrated)
	assert_eq(updated.size(), integrated, "texture_updated once a frame")
	assert_true(room.has_texture_data())
	room.finish_inpainting()
	var truth := ground_truth_faces(_dir)
	probe.resolution = truth[0].get_width()
	assert_true(probe.update_now())
	var faces := []
	for f in 6:
		faces.append(probe.get_face_image(f))
	var psnr := cubemap_psnr(faces, truth)
	var correlation := _correlation(faces, truth, [2])
	print("    coarse map at the probe vs ground truth: PSNR %.2f dB, luminance correlation %.3f (+Y face), %.3f (all)" % [psnr, correlation, _correlation(faces, truth, range(6))])
	# Looking up from the probe the truth is the coarse model's alone (ceiling tiles, the panel
	# light, the walls' tops); below the horizon it is mostly the table top, which only the dense
	# model (issue #5) can bring, so the whole sphere is printed, not judged. A map without
	# structure correlates 0; the tiles' edges are 2 cm wide, so a map off by a texel or two
	# still keeps most of the variance: ask for half of it (r > 0.7).
	assert_true(correlation > 0.7, "luminance correlation of the +Y face with the truth %.3f" % correlation)
	assert_eq(room.get_warnings().size(), 0, "no warnings: %s" % [room.get_warnings()])


## The brightest value of a face (largest channel).
static func _face_max(p_face: Image) -> float:
	var best := 0.0
	for y in p_face.get_height():
		for x in p_face.get_width():
			var c := p_face.get_pixel(x, y)
			best = maxf(best, maxf(c.r, maxf(c.g, c.b)))
	return best


## The probe's +Y face after every frame of p_recording, and the truth's.
func _ceiling_faces(p_recording: String) -> Array:
	var parts := _make_scene()
	var rig = parts[0]
	var room = parts[1]
	var probe = parts[2]
	rig.recording_path = p_recording
	assert_true(rig.open(), rig.get_last_error())
	while rig.step():
		room.integrate_rig_frame()
	room.finish_inpainting()
	var truth := ground_truth_faces(_dir)
	probe.resolution = truth[0].get_width()
	assert_true(probe.update_now())
	var map: Image = probe.get_face_image(2)
	_scene.free()
	return [map, truth[2]]


func test_a_bracketed_fisheye_gives_an_hdr_map_with_the_ceiling_light() -> void:
	_dir = fixture_bracketed_recording()
	if not need_fixture_recording(_dir):
		return
	# The ceiling panel (radiance 25) is on for the second half of the second. At the fisheye's
	# one exposure it clips at about 1; bracketed, the short frames see it whole, and the map
	# (RGBAH, never clamped) carries it to the materials.
	var bracketed := _ceiling_faces(_dir)
	var truth_max := _face_max(bracketed[1])
	var map_max := _face_max(bracketed[0])
	_dir = fixture_recording()
	var fixed := _ceiling_faces(_dir)
	var fixed_max := _face_max(fixed[0])
	print("    +Y face's brightest value: truth %.2f, bracketed %.2f, one exposure %.2f" % [truth_max, map_max, fixed_max])
	assert_true(truth_max > 20.0, "the truth shows the light (%.2f)" % truth_max)
	assert_true(map_max > 0.5 * truth_max, "the bracketed map keeps the light (%.2f of %.2f)" % [map_max, truth_max])
	assert_true(fixed_max < 0.2 * truth_max, "at one exposure the light is clipped (%.2f)" % fixed_max)


func test_without_ground_truth_pose_source_says_why() -> void:
	if not need_fixture_recording():
		return
	var parts := _make_scene()
	var room = parts[1]
	room.rig_capture = NodePath("../Nowhere")
	assert_false(room.integrate_rig_frame())
	assert_true(" ".join(room.get_warnings()).contains("does not lead to a RigCapture"), str(room.get_warnings()))


## A new room on a running engine keeps what the old one observed where its surfaces stayed
## (LiveRoom::set_room): a new atlas layout of the same room keeps it all, a room elsewhere nothing.
func test_a_new_floorplan_carries_the_texture_where_the_walls_stayed() -> void:
	if not need_fixture_recording():
		return
	var parts := _make_scene()
	var rig = parts[0]
	var room = parts[1]
	while room.get_integrated_frame_count() < 2 and rig.step():
		room.integrate_rig_frame()
	assert_eq(room.get_integrated_frame_count(), 2)
	var old_size: Vector2i = room.get_atlas_size()
	room.texel_size = 0.05
	assert_true(room.get_atlas_size() != old_size, "a new atlas layout")
	assert_eq(room.get_integrated_frame_count(), 2, "the same surfaces in the new atlas: the observations carried over")
	assert_true(room.has_texture_data())
	assert_eq(room.get_atlas_image().get_size(), room.get_atlas_size(), "the engine's atlas is the node's new layout")
	# A room 20 m away shares no surface with this one: its texture starts again.
	var far := PackedVector2Array()
	for p in room.floorplan:
		far.append(p + Vector2(20, 20))
	room.floorplan = far
	assert_eq(room.get_integrated_frame_count(), 0, "nothing of the old room lies on the new one")
	assert_false(room.has_texture_data())


## floorplan_source = Recording: the room takes the recording's floorplan and ceiling by itself (no
## floorplan typed in), from its room.yaml at once, before the recording is opened: the editor,
## where nothing opens it, shows the room too (issue #37).
func test_the_floorplan_can_come_from_the_recording() -> void:
	if not need_fixture_recording():
		return
	_scene = Node3D.new()
	var rig = fixture_rig()
	_scene.add_child(rig)
	var room = ClassDB.instantiate("CoarseRoomModel")
	room.name = "Room"
	room.texel_size = 0.05
	room.floorplan_source = 1  # FLOORPLAN_RECORDING
	room.rig_capture = NodePath("../Rig")
	_scene.add_child(room)
	add_to_tree(_scene)
	var before: PackedVector2Array = room.floorplan
	assert_true(before.size() >= 3, "the recording's room before it is opened: %s" % [before])
	assert_true(room.is_valid(), "and its mesh")
	assert_true(rig.open(), rig.get_last_error())
	await wait_frames(2)
	assert_eq(room.floorplan, rig.get_room_floorplan(), "the recording's floorplan")
	assert_eq(room.floorplan, before, "the same as read before opening")
	assert_eq(room.ceiling_height, rig.get_room_ceiling_height())
	assert_true(room.get_warnings().is_empty() or not " ".join(room.get_warnings()).contains("floorplan"), str(room.get_warnings()))
