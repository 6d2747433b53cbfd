extends SceneTree
## ./roomprobe bake-prt MESH [--out FILE] [--samples N] [--surface K]: a PRTTransfer of a mesh,
## baked and saved, from the command line (the same code as in the editor).
##   MESH   a Godot mesh resource (.tres, .res, .mesh; res:// or a path) or a Wavefront .obj
##          (v, vn, f; polygons fanned into triangles), read here into an ArrayMesh
##   --out  the PRTTransfer to write (.tres or .res; default: MESH's name + "_prt.res"); the mesh
##          is saved inside it, so its vertex order is the transfer's
## An existing --out whose cache key still matches is not baked again. Last line: a summary.


func _fail(p_message: String) -> void:
	printerr("bake-prt: " + p_message)
	quit(1)


func _load_obj(p_path: String) -> ArrayMesh:
	var text := FileAccess.get_file_as_string(p_path)
	if text.is_empty():
		return null
	var positions := PackedVector3Array()
	var normals := PackedVector3Array()
	var tool := SurfaceTool.new()
	tool.begin(Mesh.PRIMITIVE_TRIANGLES)
	var corners := []  # [position index, normal index] of each face corner, fanned
	for line in text.split("\n"):
		var parts := line.strip_edges().split(" ", false)
		if parts.is_empty():
			continue
		match parts[0]:
			"v":
				positions.append(Vector3(float(parts[1]), float(parts[2]), float(parts[3])))
			"vn":
				normals.append(Vector3(float(parts[1]), float(parts[2]), float(parts[3])).normalized())
			"f":
				var face := []
				for corner in parts.slice(1):
					var ids := corner.split("/")
					var p := int(ids[0])
					var n := int(ids[2]) if ids.size() > 2 and not ids[2].is_empty() else 0
					face.append([p - 1 if p > 0 else positions.size() + p, n - 1 if n > 0 else (normals.size() + n if n < 0 else -1)])
				for k in range(1, face.size() - 1):
					# OBJ faces are counter-clockwise; Godot's front faces are clockwise.
					corners.append_array([face[0], face[k + 1], face[k]])
	for c in corners:
		if c[0] < 0 or c[0] >= positions.size():
			return null
		if c[1] >= 0 and c[1] < normals.size():
			tool.set_normal(normals[c[1]])
		tool.add_vertex(positions[c[0]])
	if normals.is_empty():
		tool.generate_normals()
	tool.index()
	return tool.commit()


func _init() -> void:
	var args := OS.get_cmdline_user_args()
	var mesh_path := ""
	var out := ""
	var samples := 4096
	var surface := 0
	var i := 0
	while i < args.size():
		var arg: String = args[i]
		if arg in ["--out", "--samples", "--surface"] and i + 1 >= args.size():
			_fail(arg + " needs a value")
			return
		match arg:
			"--out":
				out = args[i + 1]
				i += 1
			"--samples":
				if not args[i + 1].is_valid_int() or int(args[i + 1]) < 16 or int(args[i + 1]) > 65536:
					_fail("--samples needs a whole number of directions in [16, 65536], got '%s'" % args[i + 1])
					return
				samples = int(args[i + 1])
				i += 1
			"--surface":
				if not args[i + 1].is_valid_int() or int(args[i + 1]) < 0:
					_fail("--surface needs a surface index >= 0, got '%s'" % args[i + 1])
					return
				surface = int(args[i + 1])
				i += 1
			_:
				if arg.begins_with("--") or not mesh_path.is_empty():
					_fail("unknown argument '%s' (usage: bake-prt MESH [--out FILE] [--samples N] [--surface K])" % arg)
					return
				mesh_path = arg
		i += 1
	if mesh_path.is_empty():
		_fail("which mesh? (usage: bake-prt MESH [--out FILE] [--samples N] [--surface K])")
		return
	if not FileAccess.file_exists(mesh_path):
		_fail("%s: no such file" % mesh_path)
		return
	if out.is_empty():
		out = mesh_path.get_basename() + "_prt.res"
	if not (out.ends_with(".res") or out.ends_with(".tres")):
		_fail("--out %s: must end in .res or .tres" % out)
		return
	var mesh: Mesh
	if mesh_path.get_extension().to_lower() == "obj":
		mesh = _load_obj(mesh_path)
		if mesh == null:
			_fail("%s: not a Wavefront OBJ of triangles or polygons (v, vn, f)" % mesh_path)
			return
	else:
		mesh = ResourceLoader.load(mesh_path) as Mesh
		if mesh == null:
			_fail("%s: not a Godot mesh resource" % mesh_path)
			return
	if not ClassDB.class_exists("PRTTransfer"):
		_fail("the RoomProbe extension is not loaded (build it: ./roomprobe build; the project is imported on the first run)")
		return
	var prt = ClassDB.instantiate("PRTTransfer")
	if FileAccess.file_exists(out):
		var previous = ResourceLoader.load(out, "", ResourceLoader.CACHE_MODE_IGNORE)
		if previous == null or previous.get_class() != "PRTTransfer":
			_fail("%s: exists and is not a PRTTransfer; it is not overwritten" % out)
			return
		prt = previous
	prt.mesh = mesh  # the cache key compares contents: an unchanged mesh is not baked again
	prt.surface = surface
	prt.samples_per_vertex = samples
	prt.print_progress = true
	print("bake-prt: %s, surface %d, %d vertices, %d samples a vertex" % [mesh_path, surface, prt.get_vertex_count(), prt.samples_per_vertex])
	if not prt.bake():
		_fail(prt.get_last_error())
		return
	var cached: bool = prt.get_last_bake_rays() == 0
	var err := ResourceSaver.save(prt, out)
	if err != OK:
		_fail("%s: cannot be written (error %d)" % [out, err])
		return
	var vertices: int = prt.get_vertex_count()
	print("summary: out=%s vertices=%d samples=%d cached=%d seconds=%.3f ms_per_vertex=%.4f" % [out, vertices, prt.samples_per_vertex, 1 if cached else 0,
			prt.get_last_bake_seconds(), 1000.0 * prt.get_last_bake_seconds() / maxf(1.0, vertices)])
	quit(0)
