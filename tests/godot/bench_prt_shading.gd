extends SceneTree
## The per-frame cost of PRT shading (prt_diffuse.gdshader: 7 texel reads and a 25-term dot
## product per vertex) against the same meshes with sh_diffuse.gdshader (the SH irradiance at the
## normal, per pixel), rendered by Godot. Not a test: it prints medians and one summary line.
##   ./roomprobe shell xvfb-run -a godot --path godot_project --rendering-driver vulkan -s res://tests/bench_prt_shading.gd
## Under lavapipe the "GPU" is the CPU, so the figures are of this machine's software renderer.

const Meshes := preload("res://demo_scenes/figures/figure_meshes.gd")
const COPIES := 24
const FRAMES := 60


func _init() -> void:
	var mesh := Meshes.mannequin(0.3)
	var prt = ClassDB.instantiate("PRTTransfer")
	prt.mesh = mesh
	prt.samples_per_vertex = 1024
	var start := Time.get_ticks_usec()
	if not prt.bake():
		printerr("bench: bake failed: %s" % prt.get_last_error())
		quit(1)
		return
	var bake_s := (Time.get_ticks_usec() - start) / 1e6
	var vertices: int = prt.get_vertex_count()
	print("bake: %d vertices, 1024 samples: %.2f s, %.1f us a vertex (%d rays)" % [vertices, bake_s, bake_s * 1e6 / vertices, prt.get_last_bake_rays()])
	var sh := PackedVector3Array()
	sh.resize(25)
	sh[0] = Vector3.ONE * sqrt(4.0 * PI)
	sh[2] = Vector3(0.5, 0.5, 0.5)
	var prt_material := ShaderMaterial.new()
	prt_material.shader = load("res://addons/roomprobe/shaders/prt_diffuse.gdshader")
	prt_material.set_shader_parameter("transfer", prt.get_transfer_texture())
	prt_material.set_shader_parameter("sh", sh)
	var sh_material := ShaderMaterial.new()
	sh_material.shader = load("res://addons/roomprobe/shaders/sh_diffuse.gdshader")
	sh_material.set_shader_parameter("sh", sh)
	# Alternated, so that a slow spell of this shared machine hits both; the median of each.
	var runs := {"sh_diffuse": [], "prt_diffuse": []}
	for round in 3:
		for name in ["sh_diffuse", "prt_diffuse"]:
			var ms := await _median_frame_ms(mesh, prt_material if name == "prt_diffuse" else sh_material)
			runs[name].append(ms)
			print("%-12s %d copies (%d vertices): median %.3f ms a frame (GPU time, %d frames)" % [name, COPIES, COPIES * vertices, ms, FRAMES])
	var sh_ms: float = _median(runs["sh_diffuse"])
	var prt_ms: float = _median(runs["prt_diffuse"])
	var per_vertex_ns: float = (prt_ms - sh_ms) * 1e6 / (COPIES * vertices)
	print("summary: vertices=%d bake_us_per_vertex=%.1f prt_frame_ms=%.3f sh_frame_ms=%.3f prt_over_sh_ratio=%.3f prt_extra_ns_per_vertex=%.2f mannequin_extra_ms=%.4f" % [
		vertices, bake_s * 1e6 / vertices, prt_ms, sh_ms, prt_ms / sh_ms, per_vertex_ns, per_vertex_ns * vertices / 1e6])
	quit(0)


func _median_frame_ms(mesh: Mesh, material: Material) -> float:
	var vp := SubViewport.new()
	vp.size = Vector2i(640, 480)
	vp.own_world_3d = true
	vp.render_target_update_mode = SubViewport.UPDATE_ALWAYS
	var cam := Camera3D.new()
	cam.position = Vector3(0, 0.25, 1.6)
	vp.add_child(cam)
	for i in COPIES:
		var m := MeshInstance3D.new()
		m.mesh = mesh
		m.material_override = material
		m.position = Vector3((i % 6) * 0.22 - 0.55, (i / 6) * 0.1 - 0.1, -(i / 6) * 0.3)
		vp.add_child(m)
	root.add_child(vp)
	RenderingServer.viewport_set_measure_render_time(vp.get_viewport_rid(), true)
	for i in 30:  # shaders compiled, caches warm
		await process_frame
	var times: Array[float] = []
	for i in FRAMES:
		await process_frame
		times.append(RenderingServer.viewport_get_measured_render_time_gpu(vp.get_viewport_rid()))
	vp.queue_free()
	await process_frame
	times.sort()
	return times[times.size() / 2]


func _median(values: Array) -> float:
	var sorted := values.duplicate()
	sorted.sort()
	return sorted[sorted.size() / 2]
