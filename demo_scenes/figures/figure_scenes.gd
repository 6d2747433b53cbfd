class_name FigureScenes
extends RefCounted
## The paper's figures as variants of the demo (./roomprobe demo --scene NAME): each replaces
## the demo's three objects with a figure's, every object lit by its own RoomProbe and put down
## on the real table like the demo's (main.gd). Virtual objects sit on render layer 2 and every
## probe draws that layer (RoomProbe.virtual_objects_mask), so the objects show in each other's
## maps and the contact shadow shows in the mirrors.
##
## - mirror_teapot: Figure 1, a mirror teapot.
## - water_bottle: Figure 7 (top), a refracting bottle of water (glass.gdshader, ior 1.33).
## - prt_mannequin: Figure 7 (middle), a wooden mannequin with diffuse shadowed PRT (a
##   PRTTransfer baked at start), turned, lit in its own frame (RoomProbe.sh_frame); the room's
##   ceiling light switches on half-way through the recording, as in the figure.
## - metal_teapots: Figure 7 (bottom), three metallic teapots at roughness 0.1, 0.35 and 0.7
##   (rough_metal.gdshader on the probes' GGX-prefiltered maps).
## - chrome_sphere: Figure 11, a chrome sphere with its contact shadow on the table
##   (contact_shadow.gdshader over the camera image), the shadow also in the sphere's reflection.

const NAMES := ["mirror_teapot", "water_bottle", "prt_mannequin", "metal_teapots", "chrome_sphere"]
const OBJECT_LAYER := 1 << 1
# The frames the pictures are taken from, at 15 frames a second: 3.7 s into the demo's 6-s
# recording, where the AR camera sees the table's free middle; and prt_mannequin's before the
# ceiling light switches on (at 3 s), at 2.5 s.
const PICTURE_FRAME := 55
const BEFORE_SWITCH_FRAME := 37
const Meshes := preload("res://demo_scenes/figures/figure_meshes.gd")


## Builds scene p_name under p_main (main.gd's root) in place of its three objects, each object
## under a SurfaceAnchor that puts it down on the table. Returns the objects and the probe whose
## map the demo saves; empty when p_name is unknown.
static func build(p_main: Node3D, p_name: String) -> Dictionary:
	if not p_name in NAMES:
		return {}
	for path in [^"MirrorAnchor", ^"GlassAnchor", ^"TorusAnchor"]:
		var old := p_main.get_node(path)
		p_main.remove_child(old)
		old.free()
	var objects: Array[MeshInstance3D] = []
	match p_name:
		"mirror_teapot":
			objects.append(_object(p_main, "Teapot", Meshes.teapot(0.16), _shader_material("mirror", {"tint": Vector3.ONE, "distance_aware": true}), Vector3(2.5, 0.9, 2.0), 30.0))
		"water_bottle":
			objects.append(_object(p_main, "Bottle", Meshes.water_bottle(0.24), _shader_material("glass", {"ior": 1.33, "tint": Vector3(0.96, 1.0, 0.98), "distance_aware": true}),
					Vector3(2.5, 0.9, 2.0), 0.0))
		"prt_mannequin":
			var mesh := Meshes.mannequin(0.30)
			var prt = ClassDB.instantiate("PRTTransfer")
			prt.mesh = mesh
			prt.samples_per_vertex = 512
			if not prt.bake():
				push_error("figure: the mannequin's PRT bake failed: %s" % prt.get_last_error())
			print("figure: mannequin PRT baked: %d vertices in %.2f s (%d rays)" % [prt.get_vertex_count(), prt.get_last_bake_seconds(), prt.get_last_bake_rays()])
			var material := _shader_material("prt_diffuse", {"transfer": prt.get_transfer_texture(), "albedo": Color(0.82, 0.62, 0.42)})
			var mannequin := _object(p_main, "Mannequin", mesh, material, Vector3(2.5, 0.9, 2.0), 35.0)
			mannequin.get_node("Probe").sh_frame = NodePath("..")  # the transfer is in the mesh's frame
			objects.append(mannequin)
		"metal_teapots":
			var copper := Vector3(0.95, 0.64, 0.54)
			for i in 3:
				var roughness: float = [0.1, 0.35, 0.7][i]
				objects.append(_object(p_main, "Teapot%d" % i, Meshes.teapot(0.12), _shader_material("rough_metal", {"tint": copper, "roughness": roughness}),
						Vector3(2.28 + 0.22 * i, 0.9, 2.0 + 0.05 * (i - 1)), 20.0))
		"chrome_sphere":
			var sphere_mesh := SphereMesh.new()
			sphere_mesh.radius = 0.1
			sphere_mesh.height = 0.2
			sphere_mesh.radial_segments = 96
			sphere_mesh.rings = 48
			var sphere := _object(p_main, "ChromeSphere", sphere_mesh, _shader_material("mirror", {"tint": Vector3(0.9, 0.9, 0.9), "distance_aware": true}), Vector3(2.5, 0.9, 2.0), 0.0)
			var shadow := _contact_shadow(sphere_mesh, 0.1, sphere.get_node("Probe"))
			sphere.add_child(shadow)
			# The surface's normal from the placement (the transfer is baked for a level table).
			sphere.get_parent().placed.connect(func(_at: Vector3, normal: Vector3):
				(shadow.material_override as ShaderMaterial).set_shader_parameter("plane_normal", normal))
			objects.append(sphere)
	return {"objects": objects, "probe": objects[0].get_node("Probe")}


static func _shader_material(p_shader: String, p_parameters: Dictionary) -> ShaderMaterial:
	var material := ShaderMaterial.new()
	material.shader = load("res://addons/roomprobe/shaders/%s.gdshader" % p_shader)
	for key in p_parameters:
		material.set_shader_parameter(key, p_parameters[key])
	return material


## A MeshInstance3D on the objects' layer with a RoomProbe child that feeds its material, under a
## SurfaceAnchor at p_position (its lowest point at the anchor: the anchor puts it on the table).
static func _object(p_main: Node3D, p_name: String, p_mesh: Mesh, p_material: ShaderMaterial, p_position: Vector3, p_turn_degrees: float) -> MeshInstance3D:
	var anchor = ClassDB.instantiate("SurfaceAnchor")
	anchor.name = p_name + "Anchor"
	anchor.position = Vector3(p_position.x, 0.75, p_position.z)  # about the table's height until it is found
	p_main.add_child(anchor)
	var object := MeshInstance3D.new()
	object.name = p_name
	object.mesh = p_mesh
	object.material_override = p_material
	object.layers = OBJECT_LAYER
	object.position = Vector3(0, -p_mesh.get_aabb().position.y, 0)
	object.rotation_degrees = Vector3(0, p_turn_degrees, 0)
	anchor.add_child(object)
	var probe = ClassDB.instantiate("RoomProbe")
	probe.name = "Probe"
	probe.resolution = 128
	probe.update_mode = 1  # Always
	probe.target_material = p_material
	probe.virtual_objects_mask = OBJECT_LAYER
	# Centred in the object, not at its base.
	probe.position = Vector3(0, p_mesh.get_aabb().get_center().y, 0)
	object.add_child(probe)
	probe.coarse_model = probe.get_path_to(p_main.get_node("Room"))
	probe.dense_slam = probe.get_path_to(p_main.get_node("SLAM"))
	return object


## The contact shadow under a sphere of p_radius resting on the plane (Figure 11): a plane
## whose PRTTransfer is baked with the sphere as occluder, drawn over the camera image with
## contact_shadow.gdshader, lit by the sphere's probe's SH. On the objects' layer, so the
## sphere's own probe draws the shadow into its map too.
static func _contact_shadow(p_sphere: Mesh, p_radius: float, p_probe: Node) -> MeshInstance3D:
	var plane_mesh := PlaneMesh.new()
	plane_mesh.size = Vector2(0.8, 0.8)
	plane_mesh.subdivide_width = 31
	plane_mesh.subdivide_depth = 31
	var prt = ClassDB.instantiate("PRTTransfer")
	prt.mesh = plane_mesh
	prt.samples_per_vertex = 1024
	prt.occluder = p_sphere
	prt.occluder_transform = Transform3D(Basis(), Vector3(0, p_radius, 0))
	if not prt.bake():
		push_error("figure: the contact shadow's bake failed: %s" % prt.get_last_error())
	var material := _shader_material("contact_shadow", {"transfer": prt.get_transfer_texture()})
	var plane := MeshInstance3D.new()
	plane.name = "ContactShadow"
	plane.mesh = plane_mesh
	plane.material_override = material
	plane.layers = OBJECT_LAYER
	plane.position = Vector3(0, -p_radius + 0.002, 0)  # just above the table under the sphere
	p_probe.environment_map_updated.connect(func(): material.set_shader_parameter("sh", p_probe.get_sh_coefficients()))
	return plane
