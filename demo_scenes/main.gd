extends Node3D
## RoomProbe's demo: a mirror sphere, a glass sphere and a gold torus on the real table.
##
## The synthetic living-room recording plays as if it were the live rig: its RGB image is the
## background; DenseSLAM tracks the RGB-D camera, drives the AR camera and fuses the dense model
## of the table; CoarseRoomModel textures the room from the fisheye at the poses SLAM gives; each
## sphere's RoomProbe synthesises the environment map at the sphere's centre every frame, the
## dense table over the coarse room. Once the table is meshed, each object's SurfaceAnchor puts it
## down on it (Embree). The mirror and the glass use RoomProbe's shaders (route a);
## the torus is a plain StandardMaterial3D lit by the ReflectionProbe the mirror's probe drives
## (route b) and by the sky it feeds (route c).
##
## User arguments (after --):
##   --recording DIR   the recording to play (a folder, or a .zip of one; default: the one an
##                     exported app carries, res://recordings/demo.zip, when there is one)
##   --out DIR         where to write cubemap.exr and cubemap_net.png at the end (default: none)
##   --quit-at-end     quit when the recording has played (the Movie Maker run does)
##   --true-poses      the recording's ground-truth poses instead of SLAM (evaluation mode)
##   --auto-room       no floorplan from the recording: CoarseRoomModel finds the room from the
##                     sweep (Automatic), and the room found is written to --out as room.yaml
##   --backend NAME    where the kernels with a GPU twin run: cpu (default), vulkan or auto
##                     (RigCapture.compute_backend); the summary line ends in backend=NAME and
##                     compute_fallback=yes when any went back to the CPU (RigCapture's warning)
##   --scene NAME      one of the paper's figures instead of the three objects
##                     (demo_scenes/figures/figure_scenes.gd: mirror_teapot, water_bottle,
##                     prt_mannequin, metal_teapots, chrome_sphere)

const BUNDLED_RECORDING := "res://recordings/demo.zip"  # ./roomprobe export puts one in the pack

@onready var _rig = $Rig
@onready var _room = $Room
@onready var _camera: Camera3D = $Camera3D
@onready var _video: TextureRect = $Background/Video
@onready var _probe = $MirrorAnchor/MirrorSphere/Probe
@onready var _slam = $SLAM

var _out_dir := ""
var _quit_at_end := false
var _true_poses := false
var _objects: Array[MeshInstance3D] = []  # each under a SurfaceAnchor, which puts it on the table
var _main_last := {}  # RigCapture.get_main_thread_times() at the last frame
var _main_ms: Array[float] = []  # RoomProbe's main-thread time per rendered frame
var _main_cpu_ms: Array[float] = []  # its CPU time
var _node_ms := {}  # node class -> Array of its main-thread time per rendered frame
const NODE_CLASSES := ["RigCapture", "DenseSLAM", "CoarseRoomModel", "RoomProbe", "SurfaceAnchor"]
var _objects_ms: Array[float] = []  # the saved probe's maps: drawing the other virtual objects
var _figure := ""  # the paper's figure shown (--scene), or "" for the three objects
var _frames := 0
var _auto_room := false
var _backend := "cpu"
const BACKENDS := ["cpu", "vulkan", "auto"]  # RigCapture.ComputeBackendMode's order


func _ready() -> void:
	var args := OS.get_cmdline_user_args()
	var recording := ""
	for i in args.size():
		if args[i] == "--recording" and i + 1 < args.size():
			recording = args[i + 1]
		elif args[i] == "--out" and i + 1 < args.size():
			_out_dir = args[i + 1]
		elif args[i] == "--quit-at-end":
			_quit_at_end = true
		elif args[i] == "--true-poses":
			_true_poses = true
		elif args[i] == "--auto-room":
			_auto_room = true
		elif args[i] == "--backend" and i + 1 < args.size():
			_backend = args[i + 1]
			if not BACKENDS.has(_backend):
				printerr("demo: --backend %s: one of %s" % [_backend, ", ".join(BACKENDS)])
				get_tree().quit(2)
				return
		elif args[i] == "--scene" and i + 1 < args.size() and args[i + 1] != "main":
			var figure := FigureScenes.build(self, args[i + 1])
			if figure.is_empty():
				printerr("demo: no scene %s (one of main, %s)" % [args[i + 1], ", ".join(FigureScenes.NAMES)])
				get_tree().quit(2)
				return
			_objects.assign(figure.objects)
			_probe = figure.probe
			_figure = args[i + 1]
			print("demo: scene %s" % args[i + 1])
	if _objects.is_empty():
		for path in [^"MirrorAnchor/MirrorSphere", ^"GlassAnchor/GlassSphere", ^"TorusAnchor/MetalTorus"]:
			_objects.append(get_node(path))
	if recording.is_empty() and FileAccess.file_exists(BUNDLED_RECORDING):
		recording = BUNDLED_RECORDING
	if recording.is_empty():
		printerr("demo: no recording given (-- --recording DIR); ./roomprobe demo makes one")
		get_tree().quit(2)
		return
	_rig.recording_path = recording
	_rig.compute_backend = BACKENDS.find(_backend)
	if not _rig.open():
		printerr("demo: %s" % _rig.get_last_error())
		get_tree().quit(1)
		return
	if _auto_room:
		_room.floorplan_source = 2  # FLOORPLAN_AUTOMATIC: found from the sweep, refined as it goes on
		_room.room_estimated.connect(func(state: String, message: String):
			print("demo: room %s: %s (%d corners, ceiling %.2f m)" % [state, message, _room.floorplan.size(), _room.ceiling_height]))
	else:
		_room.floorplan = _rig.get_room_floorplan()
		_room.ceiling_height = _rig.get_room_ceiling_height()
	_camera.fov = _rig.get_rgb_camera_fov()
	_rig.finished.connect(_on_finished)
	_room.texture_updated.connect(_on_texture_updated)
	_slam.tracking_state_changed.connect(func(state: int, reason: String):
		print("demo: tracking %s %s" % [["not started", "good", "poor", "lost"][state], reason]))
	for object in _objects:
		var anchor := object.get_parent()
		anchor.placed.connect(func(at: Vector3, _normal: Vector3): print("demo: %s put on the table at y = %.3f m" % [object.name, at.y]))
	_probe.environment_map_updated.connect(func(): _objects_ms.append(_probe.get_last_update_stats().get("objects_ms", 0.0)))
	if _true_poses:
		_slam.camera = NodePath()
		_room.pose_source = 0  # POSE_SOURCE_GROUND_TRUTH
	print("demo: playing %s (%d RGB-D, %d fisheye frames)" % [recording, _rig.get_frame_count(0), _rig.get_frame_count(1)])
	_rig.play()


func _process(_delta: float) -> void:
	# The nodes process first (priorities -30 to -10, the probes before this script): this
	# frame's results are in. The background is the image of the very frame whose pose the AR
	# camera has, so the two stay in register even when the pipeline lags.
	var background: Texture2D
	if _true_poses:
		background = _rig.get_rgb_texture()
	else:
		background = _slam.get_camera_image_texture()  # RigCapture's textures are then never made
	if _video.texture != background:
		_video.texture = background
	if _true_poses and _rig.has_ground_truth():
		_camera.global_transform = _rig.get_ground_truth_camera_transform()
	# RoomProbe's nodes' main-thread time since the last frame (their _process and signals).
	var times: Dictionary = RigCapture.get_main_thread_times()
	if not _main_last.is_empty():
		_main_ms.append((times.wall_usec - _main_last.wall_usec) / 1000.0)
		_main_cpu_ms.append((times.cpu_usec - _main_last.cpu_usec) / 1000.0)
		for node in NODE_CLASSES:
			var series: Array = _node_ms.get_or_add(node, [])
			series.append((times[node] - _main_last[node]) / 1000.0)
	_main_last = times
	_frames += 1
	# Figure 7 (middle) shows the mannequin before the light is switched on, half-way through.
	if _figure == "prt_mannequin" and _frames == FigureScenes.BEFORE_SWITCH_FRAME:
		_save_picture("picture_before.png")
	if not _figure.is_empty() and _frames == FigureScenes.PICTURE_FRAME:
		_save_picture("picture.png")


func _on_texture_updated(fisheye_frame: int) -> void:
	if fisheye_frame % 12 == 0:
		var stats: Dictionary = _room.get_last_frame_stats()
		var slam: Dictionary = _slam.get_stats()
		print("demo: fisheye frame %d: %d texels updated, coarse %.1f ms; SLAM frame %.1f ms (track %.1f, integrate %.1f, raycast %.1f), %d blocks" % [
			fisheye_frame, stats.texels_updated, stats.frame_ms, slam.get("frame_ms", 0.0), slam.get("track_ms", 0.0),
			slam.get("integrate_ms", 0.0), slam.get("raycast_ms", 0.0), slam.get("allocated_blocks", 0)])


func _on_finished() -> void:
	_print_summary()
	_room.finish_inpainting()
	_probe.update_now()
	if _auto_room:
		_room.estimate_room_now()  # the whole sweep (the worker's last estimate may be up to 2 s old)
		_report_room()
	if not _out_dir.is_empty():
		DirAccess.make_dir_recursive_absolute(_out_dir)
		if _auto_room and _room.is_valid():
			var room_path := _out_dir.path_join("room.yaml")
			print("demo: %s %s" % ["wrote" if _room.save_room(room_path, true) == OK else "could not write", room_path])
		for item in [["cubemap.exr", _probe.save_exr], ["cubemap_net.png", _probe.save_png_net]]:
			var path: String = _out_dir.path_join(item[0])
			var err: int = item[1].call(path)
			print("demo: %s %s" % ["wrote" if err == OK else "could not write", path])
	if _quit_at_end:
		get_tree().quit(0)


## The frame on screen, cropped to the figure's objects and doubled, into --out (the pictures of README and docs/USAGE.md).
func _save_picture(p_name: String) -> void:
	if _out_dir.is_empty():
		return
	var frame := get_viewport().get_texture().get_image()
	var centre := Vector3()
	for object in _objects:
		centre += object.global_transform * object.get_aabb().get_center()
	var at := _camera.unproject_position(centre / _objects.size())
	var size := Vector2i(240, 160)
	var corner := Vector2i(clampi(int(at.x) - size.x / 2, 0, frame.get_width() - size.x), clampi(int(at.y) - size.y / 2, 0, frame.get_height() - size.y))
	var picture := frame.get_region(Rect2i(corner, size))
	picture.resize(size.x * 2, size.y * 2, Image.INTERPOLATE_NEAREST)
	DirAccess.make_dir_recursive_absolute(_out_dir)
	var path := _out_dir.path_join(p_name)
	print("demo: %s %s" % ["wrote" if picture.save_png(path) == OK else "could not write", path])


## The room found against the recording's own (the recording's world is its true room's: tracking
## starts at its initial_rgb_pose), one key=value line.
func _report_room() -> void:
	if not _room.is_valid():
		print("demo: room_found=no %s" % _room.get_room_estimate())
		return
	var found := []
	for p in _room.floorplan:
		found.append(_room.global_transform * Vector3(p.x, 0.0, p.y))
	var worst := 0.0
	var truth: PackedVector2Array = _rig.get_room_floorplan()
	for pair in [[found, truth], [truth, found]]:
		for p in pair[0]:
			var a: Vector3 = p if p is Vector3 else Vector3(p.x, 0.0, p.y)
			var nearest := INF
			for q in pair[1]:
				nearest = minf(nearest, a.distance_to(q if q is Vector3 else Vector3(q.x, 0.0, q.y)))
			worst = maxf(worst, nearest)
	print("demo: room_found=yes state=%s corners=%d corner_error_max_m=%.4f ceiling_error_m=%.4f" % [
		_room.get_room_estimate().get("state", "?"), found.size(), worst, absf(_room.ceiling_height - _rig.get_room_ceiling_height())])


## One line of key=value pairs: the main-thread time per rendered frame, and the engine's latency
## and dropped frames (DenseSLAM.get_stats()), and the median time the saved probe spent drawing
## the other virtual objects into its maps.
func _print_summary() -> void:
	var rank := func(values: Array[float], fraction: float) -> float:
		var sorted := values.duplicate()
		sorted.sort()
		return sorted[clampi(ceili(fraction * sorted.size()) - 1, 0, sorted.size() - 1)] if not sorted.is_empty() else 0.0
	var slam: Dictionary = _slam.get_stats()
	var fallback := false
	for warning in _rig.get_warnings():
		if warning.begins_with("compute_backend"):
			fallback = true
			print("demo: %s" % warning)
	# Where the main-thread time goes: each node class's median and mean per rendered frame.
	var by_node := []
	for node in NODE_CLASSES:
		var series: Array[float] = []
		series.assign(_node_ms.get(node, []))
		var total := 0.0
		for value in series:
			total += value
		by_node.append("%s %.2f/%.2f" % [node, rank.call(series, 0.5), total / maxi(series.size(), 1)])
	print("demo: main thread per frame by node, median/mean ms: %s" % ", ".join(by_node))
	print("demo: summary frames=%d main_thread_ms_p50=%.3f main_thread_ms_p95=%.3f main_thread_ms_max=%.3f main_thread_cpu_ms_p50=%.3f latency_ms_p50=%.1f latency_ms_p95=%.1f dropped_rgbd=%d dropped_capture=%d objects_ms_p50=%.2f backend=%s compute_fallback=%s" % [
		_main_ms.size(), rank.call(_main_ms, 0.5), rank.call(_main_ms, 0.95), rank.call(_main_ms, 1.0), rank.call(_main_cpu_ms, 0.5), slam.get("latency_ms_p50", 0.0),
		slam.get("latency_ms_p95", 0.0), slam.get("dropped_frames", 0), _rig.get_dropped_frame_count(), rank.call(_objects_ms, 0.5), _backend, "yes" if fallback else "no"])
