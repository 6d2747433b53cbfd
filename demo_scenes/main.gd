extends Node3D
## RoomProbe's demo: a mirror sphere, a glass sphere and a gold torus on the real table.
##
## The synthetic living-room recording plays as if it were the live rig: its RGB image is the
## background, the AR camera follows the RGB camera (the recording's ground-truth poses until
## DenseSLAM tracks, issue #5), CoarseRoomModel textures the room from the fisheye, and each
## sphere's RoomProbe synthesises the environment map at the sphere's centre every frame. The
## mirror and the glass use RoomProbe's shaders (route a); the torus is a plain
## StandardMaterial3D lit by the ReflectionProbe the mirror's probe drives (route b) and by the
## sky it feeds (route c).
##
## User arguments (after --):
##   --recording DIR   the recording to play (required)
##   --out DIR         where to write cubemap.exr and cubemap_net.png at the end (default: none)
##   --quit-at-end     quit when the recording has played (the Movie Maker run does)

@onready var _rig = $Rig
@onready var _room = $Room
@onready var _camera: Camera3D = $Camera3D
@onready var _video: TextureRect = $Background/Video
@onready var _probe = $MirrorSphere/Probe

var _out_dir := ""
var _quit_at_end := false


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
	print("demo: playing %s (%d RGB-D, %d fisheye frames)" % [recording, _rig.get_frame_count(0), _rig.get_frame_count(1)])
	_rig.play()


func _process(_delta: float) -> void:
	# RigCapture processes first (priority -30): this frame's image and pose are in.
	if _video.texture != _rig.get_rgb_texture():
		_video.texture = _rig.get_rgb_texture()
	if _rig.has_ground_truth():
		_camera.global_transform = _rig.get_ground_truth_camera_transform()


func _on_texture_updated(fisheye_frame: int) -> void:
	if fisheye_frame % 12 == 0:
		var stats: Dictionary = _room.get_last_frame_stats()
		print("demo: fisheye frame %d: %d texels updated, pipeline %.1f ms" % [fisheye_frame, stats.texels_updated, stats.frame_ms])


func _on_finished() -> void:
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
