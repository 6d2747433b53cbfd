extends Node3D
## RoomProbe's demo: a mirror sphere, a glass sphere and a gold torus on the real table.
##
## The synthetic living-room recording plays as if it were the live rig: its RGB image is the
## background; DenseSLAM tracks the RGB-D camera, drives the AR camera and fuses the dense model
## of the table; CoarseRoomModel textures the room from the fisheye at the poses SLAM gives; each
## sphere's RoomProbe synthesises the environment map at the sphere's centre every frame, the
## dense table over the coarse room. Once the table is meshed, the objects are put down on it by
## DenseSLAM.place_on_ray (Embree). The mirror and the glass use RoomProbe's shaders (route a);
## the torus is a plain StandardMaterial3D lit by the ReflectionProbe the mirror's probe drives
## (route b) and by the sky it feeds (route c).
##
## User arguments (after --):
##   --recording DIR   the recording to play (required)
##   --out DIR         where to write cubemap.exr and cubemap_net.png at the end (default: none)
##   --quit-at-end     quit when the recording has played (the Movie Maker run does)
##   --true-poses      the recording's ground-truth poses instead of SLAM (evaluation mode)

@onready var _rig = $Rig
@onready var _room = $Room
@onready var _camera: Camera3D = $Camera3D
@onready var _video: TextureRect = $Background/Video
@onready var _probe = $MirrorSphere/Probe
@onready var _slam = $SLAM

var _out_dir := ""
var _quit_at_end := false
var _true_poses := false
var _placed := false
var _main_usec_last := -1
var _main_ms: Array[float] = []  # RoomProbe's main-thread time per rendered frame


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
	if recording.is_empty():
		printerr("demo: no recording given (-- --recording DIR); ./roomprobe demo makes one")
		get_tree().quit(2)
		return
	_rig.recording_path = recording
	if not _rig.open():
		printerr("demo: %s" % _rig.get_last_error())
		get_tree().quit(1)
		return
	_room.floorplan = _rig.get_room_floorplan()
	_room.ceiling_height = _rig.get_room_ceiling_height()
	_camera.fov = _rig.get_rgb_camera_fov()
	_rig.finished.connect(_on_finished)
	_room.texture_updated.connect(_on_texture_updated)
	_slam.tracking_state_changed.connect(func(state: int, reason: String):
		print("demo: tracking %s %s" % [["not started", "good", "poor", "lost"][state], reason]))
	_slam.mesh_updated.connect(_place_objects)
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
	var usec: int = RigCapture.get_main_thread_usec()
	if _main_usec_last >= 0:
		_main_ms.append((usec - _main_usec_last) / 1000.0)
	_main_usec_last = usec


func _on_texture_updated(fisheye_frame: int) -> void:
	if fisheye_frame % 12 == 0:
		var stats: Dictionary = _room.get_last_frame_stats()
		var slam: Dictionary = _slam.get_stats()
		print("demo: fisheye frame %d: %d texels updated, coarse %.1f ms; SLAM frame %.1f ms (track %.1f, integrate %.1f, raycast %.1f), %d blocks" % [
			fisheye_frame, stats.texels_updated, stats.frame_ms, slam.get("frame_ms", 0.0), slam.get("track_ms", 0.0),
			slam.get("integrate_ms", 0.0), slam.get("raycast_ms", 0.0), slam.get("allocated_blocks", 0)])


## Puts each object down on the real surface below it, once the table is in the dense mesh.
func _place_objects() -> void:
	if _placed:
		return
	for path in [^"MirrorSphere", ^"GlassSphere", ^"MetalTorus"]:
		var object: MeshInstance3D = get_node(path)
		var above := Vector3(object.position.x, 1.6, object.position.z)
		var hit: Dictionary = _slam.place_on_ray(above, Vector3.DOWN)
		if hit.get("surface", "") != "dense":
			return  # the table is not meshed there yet: try again at the next mesh
		var half_height: float = object.get_aabb().size.y * 0.5 * object.scale.y
		object.position.y = hit.position.y + half_height
		print("demo: %s put on the %s surface at y = %.3f m" % [path, hit.surface, hit.position.y])
	_placed = true


func _on_finished() -> void:
	_print_summary()
	_room.finish_inpainting()
	_probe.update_now()
	if not _out_dir.is_empty():
		DirAccess.make_dir_recursive_absolute(_out_dir)
		for item in [["cubemap.exr", _probe.save_exr], ["cubemap_net.png", _probe.save_png_net]]:
			var path: String = _out_dir.path_join(item[0])
			var err: int = item[1].call(path)
			print("demo: %s %s" % ["wrote" if err == OK else "could not write", path])
	if _quit_at_end:
		get_tree().quit(0)


## One line of key=value pairs: the main-thread time per rendered frame, and the engine's latency
## and dropped frames (DenseSLAM.get_stats()).
func _print_summary() -> void:
	var sorted := _main_ms.duplicate()
	sorted.sort()
	var rank := func(fraction: float) -> float:
		return sorted[clampi(ceili(fraction * sorted.size()) - 1, 0, sorted.size() - 1)] if not sorted.is_empty() else 0.0
	var slam: Dictionary = _slam.get_stats()
	print("demo: summary frames=%d main_thread_ms_p50=%.3f main_thread_ms_p95=%.3f main_thread_ms_max=%.3f latency_ms_p50=%.1f latency_ms_p95=%.1f dropped_rgbd=%d dropped_capture=%d" % [
		sorted.size(), rank.call(0.5), rank.call(0.95), rank.call(1.0), slam.get("latency_ms_p50", 0.0), slam.get("latency_ms_p95", 0.0),
		slam.get("dropped_frames", 0), _rig.get_dropped_frame_count()])
