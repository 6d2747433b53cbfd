extends RoomProbeTestCase
## Issue #17's node properties: every setter keeps its property within what its hint promises.
## A number out of range is clamped with a warning, a non-number refused with an error, an enum
## value outside its list refused with an error (the property keeps its value), and a layer mask
## keeps only Godot's 20 render layers. docs/bad-input.md lists each case.

const ALL_LAYERS := (1 << 20) - 1

var _nodes: Array[Object] = []


func after_each() -> void:
	for n in _nodes:
		if n is Node and is_instance_valid(n):
			n.free()
	_nodes.clear()


func _make(p_class: String) -> Object:
	var o = ClassDB.instantiate(p_class)
	_nodes.append(o)
	return o


func test_enums_outside_their_list_are_refused() -> void:
	var room = _make("CoarseRoomModel")
	for property in ["pose_source", "floorplan_source", "lighting_compensation"]:
		var before: int = room.get(property)
		for bad in [-1, 1000000000]:
			expect_error("CoarseRoomModel.%s must be one of 0.." % property)
			room.set(property, bad)
			assert_eq(room.get(property), before, "%s = %d is refused" % [property, bad])
	var probe = _make("RoomProbe")
	expect_error("RoomProbe.update_mode must be one of 0..1; got 7")
	probe.update_mode = 7
	assert_eq(probe.update_mode, 0)
	var rig = _make("RigCapture")
	expect_error("RigCapture.pacing must be one of 0..1; got -1")
	rig.pacing = -1
	assert_eq(rig.pacing, 0)
	expect_error("RigCapture.source (0 Recording, 1 Live) must be one of 0..1; got 9")
	rig.source = 9
	assert_eq(rig.source, 0)
	expect_error("RigCapture.fisheye_backend (0 Aravis, 1 UVC, 2 Camera Feed) must be one of 0..2; got -1")
	rig.fisheye_backend = -1
	assert_eq(rig.fisheye_backend, 0)


func test_numbers_out_of_range_are_clamped_with_a_warning() -> void:
	var room = _make("CoarseRoomModel")
	# 1e-300 m once made the atlas's texel count overflow (-9223372036854775808 in the message).
	expect_warning("CoarseRoomModel.texel_size must be within [0.001, 1] m; got 1e-300")
	room.texel_size = 1e-300
	assert_eq(room.texel_size, 0.001)
	expect_error("CoarseRoomModel.texel_size must be a finite number")
	room.texel_size = NAN
	assert_eq(room.texel_size, 0.001)
	var probe = _make("RoomProbe")
	expect_warning("RoomProbe.resolution must be within [8, 4096] texels; got 100000")
	probe.resolution = 100000
	assert_eq(probe.resolution, 4096)
	expect_warning("RoomProbe.resolution must be within [8, 4096] texels; got -5")
	probe.resolution = -5
	assert_eq(probe.resolution, 8)
	var slam = _make("DenseSLAM")
	expect_warning("DenseSLAM.max_blocks must be within [1, 4194304]")
	slam.max_blocks = 0
	assert_eq(slam.max_blocks, 1)
	expect_warning("DenseSLAM.voxel_size must be within [0.002, 0.1] m")
	slam.voxel_size = 5.0
	assert_eq(slam.voxel_size, 0.1)
	expect_warning("DenseSLAM.mesh_upload_budget must be within [0, 1000000] triangles")
	slam.mesh_upload_budget = -3
	assert_eq(slam.mesh_upload_budget, 0)
	var anchor = _make("SurfaceAnchor")
	expect_warning("SurfaceAnchor.search_height must be within [0.01, 100] m; got -1")
	anchor.search_height = -1.0
	assert_eq(anchor.search_height, 0.01)
	var prt = ClassDB.instantiate("PRTTransfer")
	expect_warning("PRTTransfer.samples_per_vertex must be within [16, 65536]; got 1")
	prt.samples_per_vertex = 1
	assert_eq(prt.samples_per_vertex, 16)
	expect_warning("PRTTransfer.surface must be within [0, 255]; got -2")
	prt.surface = -2
	assert_eq(prt.surface, 0)


## Issue #38: max_blocks at the top of its range (4194304 blocks, a 24.2 GiB model when full) gave a
## bare std::bad_alloc when the model was made. A cap whose full model needs more than the machine's
## memory is refused at once, naming the memory it needs; one that fits is taken.
func test_max_blocks_beyond_the_machines_memory_is_refused_naming_the_memory() -> void:
	var slam = _make("DenseSLAM")
	slam.max_blocks = 50000
	# 6164 bytes a block (voxels and bookkeeping) and a hash table of 2^23 slots of 16 bytes.
	var needed := 4194304 * 6164 + (1 << 23) * 16
	if int(OS.get_memory_info()["physical"]) < needed:
		expect_error("DenseSLAM.max_blocks 4194304 needs 24.2 GiB of memory when the model is full")
		slam.max_blocks = 4194304
		assert_eq(slam.max_blocks, 50000, "refused: the property keeps its value")
	else:
		slam.max_blocks = 4194304
		assert_eq(slam.max_blocks, 4194304, "fits this machine's memory")


func test_layer_masks_keep_the_20_render_layers() -> void:
	var room = _make("CoarseRoomModel")
	expect_warning("CoarseRoomModel.room_layers has bits above the 20 render layers")
	room.room_layers = -1
	assert_eq(room.room_layers, ALL_LAYERS)
	var probe = _make("RoomProbe")
	expect_warning("RoomProbe.virtual_objects_mask has bits above the 20 render layers")
	probe.virtual_objects_mask = 1000000000
	assert_eq(probe.virtual_objects_mask, 1000000000 & ALL_LAYERS)
	# Within the 20 layers: kept as given, no warning asked for.
	probe.virtual_objects_mask = 6
	assert_eq(probe.virtual_objects_mask, 6)
