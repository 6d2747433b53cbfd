extends RoomProbeTestCase
## The paper's figures as demo scenes (demo_scenes/figures/figure_scenes.gd): each replaces the
## demo's three objects with its own, every object with a RoomProbe that feeds its material and
## draws the others (the objects' layer); an unknown name changes nothing. The demo itself
## (./roomprobe demo --scene NAME) plays them; this checks how they are put together.

const Figures := preload("res://demo_scenes/figures/figure_scenes.gd")

var _main: Node3D


func after_each() -> void:
	if is_instance_valid(_main):
		_main.free()
	_main = null


## What main.tscn gives the builder: the three objects, the room and the SLAM node.
func _fake_main() -> Node3D:
	var main := Node3D.new()
	for name in ["MirrorAnchor", "GlassAnchor", "TorusAnchor"]:
		var anchor = ClassDB.instantiate("SurfaceAnchor")
		anchor.name = name
		main.add_child(anchor)
	var room = ClassDB.instantiate("CoarseRoomModel")
	room.name = "Room"
	main.add_child(room)
	var slam = ClassDB.instantiate("DenseSLAM")
	slam.name = "SLAM"
	main.add_child(slam)
	add_to_tree(main)
	return main


func test_every_figure_builds_its_objects_with_their_probes() -> void:
	var expected := {"mirror_teapot": ["mirror"], "water_bottle": ["glass"], "prt_mannequin": ["prt_diffuse"],
			"metal_teapots": ["rough_metal", "rough_metal", "rough_metal"], "chrome_sphere": ["mirror"]}
	assert_eq(Figures.NAMES.size(), expected.size())
	for name in Figures.NAMES:
		_main = _fake_main()
		var figure: Dictionary = Figures.build(_main, name)
		assert_false(figure.is_empty(), name)
		assert_null(_main.get_node_or_null("MirrorAnchor"), "%s: the demo's objects are gone" % name)
		var objects: Array = figure.objects
		assert_eq(objects.size(), expected[name].size(), name)
		for i in objects.size():
			var object: MeshInstance3D = objects[i]
			var probe = object.get_node("Probe")
			var material: ShaderMaterial = object.material_override
			assert_true(material.shader.resource_path.ends_with("/%s.gdshader" % expected[name][i]), "%s: %s" % [name, material.shader.resource_path])
			assert_eq(probe.target_material, material, "%s: the probe feeds the object's material" % name)
			assert_eq(probe.virtual_objects_mask, Figures.OBJECT_LAYER, "%s: the probe draws the other objects" % name)
			assert_eq(object.layers, Figures.OBJECT_LAYER)
			assert_eq(probe.get_node(probe.coarse_model), _main.get_node("Room"))
			assert_eq(object.get_parent().get_class(), "SurfaceAnchor", "%s: put on the table by an anchor" % name)
			assert_near(object.position.y + object.get_aabb().position.y, 0.0, 1e-4, "%s: its lowest point at the anchor" % name)
		assert_eq(figure.probe, objects[0].get_node("Probe"))
		if name == "prt_mannequin":
			assert_not_null(objects[0].material_override.get_shader_parameter("transfer"), "the mannequin's transfer was baked")
			assert_eq(objects[0].get_node("Probe").sh_frame, NodePath(".."), "lit in its own frame")
		if name == "chrome_sphere":
			var shadow: MeshInstance3D = objects[0].get_node("ContactShadow")
			assert_true((shadow.material_override as ShaderMaterial).shader.resource_path.ends_with("/contact_shadow.gdshader"))
			assert_eq(shadow.layers, Figures.OBJECT_LAYER, "the shadow is in the sphere's own map")
		_main.free()
	_main = _fake_main()
	assert_true(Figures.build(_main, "no_such_figure").is_empty())
	assert_not_null(_main.get_node_or_null("MirrorAnchor"), "an unknown name changes nothing")
