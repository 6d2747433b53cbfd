extends RoomProbeTestCase
## RigCapture plays the synthetic living-room recording (1 s, rendered by the test runner with
## build/bin/roomprobe_synth) in step mode: frame counts, timestamps and pixel values are
## checked against the recording's own files, read here without RoomProbe.

var _rig  # RigCapture
var _dir := ""


func before_each() -> void:
	_dir = fixture_recording()
	_rig = ClassDB.instantiate("RigCapture")
	_rig.autoplay = false
	_rig.pacing = 1  # PACING_STEP


func after_each() -> void:
	if is_instance_valid(_rig):
		_rig.free()
	_rig = null


# The "timestamp path" lines of a frame index, without comments.
func _index(file_name: String) -> Array:
	var rows: Array = []
	var f := FileAccess.open(_dir.path_join(file_name), FileAccess.READ)
	while f and not f.eof_reached():
		var line := f.get_line().strip_edges()
		if line.is_empty() or line.begins_with("#"):
			continue
		var parts := line.split(" ", false)
		rows.append([float(parts[0]), parts[1]])
	return rows


func test_plays_every_frame_in_step_mode() -> void:
	if not need_fixture_recording():
		return
	var rgb := _index("rgb.txt")
	var fisheye := _index("fisheye.txt")
	_rig.recording_path = _dir
	assert_true(_rig.open(), "opens: %s" % _rig.get_last_error())
	assert_eq(_rig.get_frame_count(0), rgb.size(), "RGB-D frames")
	assert_eq(_rig.get_frame_count(1), fisheye.size(), "fisheye frames")
	assert_eq(_rig.get_event_count(), rgb.size() + fisheye.size(), "events of both streams")
	var seen := {0: [], 1: []}
	var finished := [0]
	_rig.frame_captured.connect(func(stream, index, timestamp): seen[stream].append([index, timestamp]))
	_rig.finished.connect(func(): finished[0] += 1)
	var last_time := -1.0
	while _rig.step():
		assert_true(_rig.get_time() >= last_time, "playback time never goes back")
		last_time = _rig.get_time()
	assert_eq(finished[0], 1, "finished once at the end")
	assert_false(_rig.step(), "no frame after the end without loop")
	assert_eq(seen[0].size(), rgb.size())
	assert_eq(seen[1].size(), fisheye.size())
	for i in seen[0].size():
		assert_eq(seen[0][i][0], i, "RGB-D frames in order")
		assert_near(seen[0][i][1], rgb[i][0], 1e-9, "RGB-D timestamp %d" % i)
	for i in seen[1].size():
		assert_near(seen[1][i][1], fisheye[i][0], 1e-9, "fisheye timestamp %d" % i)


# A frame file read by Godot alone: a PNG, or a raw frame (docs/recording-format.md: a 32-byte
# header, then one zstd frame of the samples, colour as R, G, B), which Godot's own zstd unpacks.
func _load_frame(path: String) -> Image:
	if not path.ends_with(".zst"):
		return Image.load_from_file(path)
	var bytes := FileAccess.get_file_as_bytes(path)
	assert_eq(bytes.slice(8, 12).get_string_from_ascii(), "RPRF", "%s has the raw frame header" % path)
	assert_eq(bytes[14], 1, "%s holds 8-bit samples" % path)
	var width := bytes.decode_u32(16)
	var height := bytes.decode_u32(20)
	var channels: int = bytes[15]
	var samples := bytes.slice(32).decompress(width * height * channels, FileAccess.COMPRESSION_ZSTD)
	return Image.create_from_data(width, height, false, Image.FORMAT_RGB8 if channels == 3 else Image.FORMAT_L8, samples)


func _step_to(stream: int, index: int) -> void:
	while _rig.get_frame_index(stream) != index and _rig.step():
		pass


func test_pixels_of_a_known_frame() -> void:
	if not need_fixture_recording():
		return
	_rig.recording_path = _dir
	assert_true(_rig.open())
	_step_to(0, 5)
	assert_eq(_rig.get_frame_index(0), 5)
	var expected := _load_frame(_dir.path_join(_index("rgb.txt")[5][1]))
	expected.convert(Image.FORMAT_RGB8)
	var shown: Image = _rig.get_rgb_image()
	assert_eq(_rig.get_rgb_texture().get_size(), Vector2(640, 480), "the texture shows it")
	assert_eq(shown.get_size(), Vector2i(640, 480))
	assert_eq(shown.get_format(), Image.FORMAT_RGB8)
	assert_true(shown.get_data() == expected.get_data(), "RGB frame 5 equals rgb/%s decoded by Godot" % _index("rgb.txt")[5][1])
	var depth: Image = _rig.get_depth_image()
	assert_eq(depth.get_format(), Image.FORMAT_RF, "depth in metres as floats")
	var centre := depth.get_pixel(320, 240).r
	assert_true(centre > 0.3 and centre < 8.0, "depth at the centre is inside the room: %f m" % centre)
	_step_to(1, 3)
	var fish_expected := _load_frame(_dir.path_join(_index("fisheye.txt")[3][1]))
	var fish: Image = _rig.get_fisheye_image()
	fish_expected.convert(fish.get_format())
	assert_eq(fish.get_size(), Vector2i(1024, 1024))
	assert_true(fish.get_data() == fish_expected.get_data(), "fisheye frame 3 equals its file decoded by Godot")


func test_missing_recording_is_a_clear_error() -> void:
	# open() reports it, and step() tries to open once more.
	expect_error("no_such_recording")
	expect_error("no_such_recording")
	_rig.recording_path = _dir.path_join("no_such_recording")
	assert_false(_rig.open())
	assert_true(_rig.get_last_error().contains("no_such_recording"), "the error names the folder: %s" % _rig.get_last_error())
	assert_true(" ".join(_rig.get_warnings()).contains("cannot be played"), "and shows as a warning")
	assert_false(_rig.step(), "nothing plays")


## Before anything opens them (the editor), the warnings already say when recording_path or
## rig_file cannot be used, naming the input, and say nothing for good ones.
func test_unopened_inputs_are_checked_for_the_editor() -> void:
	if not need_fixture_recording():
		return
	_rig.recording_path = _dir.path_join("no_such_recording")
	var text := " ".join(_rig.get_warnings())
	assert_true(text.contains("recording_path cannot be played") and text.contains("no_such_recording"), text)
	_rig.recording_path = _dir
	assert_false(" ".join(_rig.get_warnings()).contains("cannot be played"), " ".join(_rig.get_warnings()))
	var bad := OS.get_user_data_dir().path_join("roomprobe_bad_rig.yaml")
	var f := FileAccess.open(bad, FileAccess.WRITE)
	f.store_string("schema_version: 2\nrgb: [not, a, camera\n")
	f.close()
	_rig.source = 1  # SOURCE_LIVE
	_rig.rig_file = bad
	text = " ".join(_rig.get_warnings())
	DirAccess.remove_absolute(bad)
	assert_true(text.contains("rig_file cannot be read") and text.contains("roomprobe_bad_rig.yaml"), text)
	_rig.rig_file = _dir.path_join("rig.yaml")
	assert_false(" ".join(_rig.get_warnings()).contains("cannot be read"), " ".join(_rig.get_warnings()))
	# A Godot camera feed as the fisheye takes no exposure: asking for one is a warning, not silence.
	_rig.fisheye_backend = 2  # FISHEYE_BACKEND_CAMERA_FEED
	assert_false(" ".join(_rig.get_warnings()).contains("Camera Feed"), " ".join(_rig.get_warnings()))
	_rig.auto_exposure = false
	text = " ".join(_rig.get_warnings())
	assert_true(text.contains("Camera Feed") and text.contains("exposure_us"), text)
	_rig.auto_exposure = true
	_rig.fisheye_backend = 0


# The recording folder zipped with ZIPPacker under one top-level folder, as ./roomprobe export does.
func _zip_recording(zip_path: String, top: String) -> void:
	var packer := ZIPPacker.new()
	assert_eq(packer.open(zip_path), OK, "writes the test zip")
	var stack := [""]
	while not stack.is_empty():
		var rel: String = stack.pop_back()
		var dir := DirAccess.open(_dir.path_join(rel))
		for sub in dir.get_directories():
			stack.append(rel.path_join(sub))
		for file in dir.get_files():
			packer.start_file(top.path_join(rel.path_join(file)).simplify_path())
			packer.write_file(FileAccess.get_file_as_bytes(_dir.path_join(rel.path_join(file))))
			packer.close_file()
	packer.close()


## A zipped recording plays like its folder (an exported app carries one in its pack: res://...zip);
## it is unpacked once into user://roomprobe/unpacked/, and a zip whose entries would land outside
## that folder is refused, naming the entry.
func test_zipped_recording_plays_and_zip_slip_is_refused() -> void:
	if not need_fixture_recording():
		return
	var zip_path := OS.get_user_data_dir().path_join("roomprobe_test_recording.zip")
	_zip_recording(zip_path, "living")
	_rig.recording_path = zip_path
	assert_true(_rig.open(), "opens the zip: %s" % _rig.get_last_error())
	assert_eq(_rig.get_frame_count(0), _index("rgb.txt").size(), "every RGB-D frame of the folder")
	assert_eq(_rig.get_frame_count(1), _index("fisheye.txt").size(), "every fisheye frame of the folder")
	var frames := 0
	while _rig.step():
		frames += 1
	assert_eq(frames, _index("rgb.txt").size() + _index("fisheye.txt").size(), "plays every frame")
	DirAccess.remove_absolute(zip_path)

	# Issue #38: unpacked recordings piled up in user://. A half-unpacked folder (a killed unpack)
	# and one unused for a week are removed when a zip is next opened; the one opened is kept.
	var unpacked := OS.get_user_data_dir().path_join("roomprobe/unpacked")
	DirAccess.make_dir_recursive_absolute(unpacked.path_join("killed-0123456789ab.partial/living"))
	DirAccess.make_dir_recursive_absolute(unpacked.path_join("old-0123456789ab/living"))
	var stamp := FileAccess.open(unpacked.path_join("old-0123456789ab/.roomprobe-unpacked"), FileAccess.WRITE)
	stamp.store_string("old\n")
	stamp.close()
	OS.execute("touch", ["-d", "10 days ago", unpacked.path_join("old-0123456789ab/.roomprobe-unpacked")])
	_zip_recording(zip_path, "living")
	_rig.recording_path = zip_path
	assert_true(_rig.open(), "opens the zip again: %s" % _rig.get_last_error())
	assert_false(DirAccess.dir_exists_absolute(unpacked.path_join("killed-0123456789ab.partial")), "a half-unpacked folder is removed")
	assert_false(DirAccess.dir_exists_absolute(unpacked.path_join("old-0123456789ab")), "a folder unused for 10 days is removed")
	var kept := Array(DirAccess.get_directories_at(unpacked)).filter(func(n: String) -> bool: return n.begins_with("roomprobe_test_recording-"))
	assert_true(kept.size() >= 1, "the recording opened is kept")
	assert_true(_rig.step(), "and plays")
	_rig.close()
	DirAccess.remove_absolute(zip_path)
	for name in kept:  # this test's own, from this and earlier runs
		remove_folder(unpacked.path_join(name))

	var evil := OS.get_user_data_dir().path_join("roomprobe_test_evil.zip")
	var packer := ZIPPacker.new()
	packer.open(evil)
	packer.start_file("living/../../escaped.txt")
	packer.write_file("x".to_utf8_buffer())
	packer.close_file()
	packer.close()
	expect_error("would land outside")
	_rig.recording_path = evil
	assert_false(_rig.open(), "refused")
	assert_true(_rig.get_last_error().contains("living/../../escaped.txt"), "names the entry: %s" % _rig.get_last_error())
	assert_false(FileAccess.file_exists(OS.get_user_data_dir().path_join("roomprobe/escaped.txt")), "nothing written outside")
	DirAccess.remove_absolute(evil)


## Issue #38: a zip bomb inflated without limit into user://. An entry that would inflate more than
## 100-fold (64 MiB of zeros, some 64 KiB zipped) is refused before a byte is inflated, naming the
## zip and the entry; nothing is left in user://roomprobe/unpacked/, whole or partial.
func test_a_zip_bomb_is_refused_before_anything_is_unpacked() -> void:
	var bomb := OS.get_user_data_dir().path_join("roomprobe_test_bomb.zip")
	var packer := ZIPPacker.new()
	assert_eq(packer.open(bomb), OK, "writes the test zip")
	packer.start_file("living/rig.yaml")
	packer.write_file(FileAccess.get_file_as_bytes(repo_path("calib/synthetic_rig.yaml")))
	packer.close_file()
	packer.start_file("living/rgb/000000.zst")
	var zeros := PackedByteArray()
	zeros.resize(64 << 20)
	packer.write_file(zeros)
	packer.close_file()
	packer.close()
	expect_error("inflates")
	_rig.recording_path = bomb
	assert_false(_rig.open(), "refused")
	var error: String = _rig.get_last_error()
	assert_true(error.contains("roomprobe_test_bomb.zip: entry 'living/rgb/000000.zst' inflates") and error.contains("more than the 100-fold"), error)
	var unpacked := OS.get_user_data_dir().path_join("roomprobe/unpacked")
	for name in DirAccess.get_directories_at(unpacked):
		assert_false(name.begins_with("roomprobe_test_bomb"), "nothing unpacked: " + name)
	DirAccess.remove_absolute(bomb)

