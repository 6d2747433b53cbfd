#include "room_probe.h"

#include "coarse_room_model.h"

#include "../convert/image_convert.h"

using namespace godot;

namespace roomprobe {

RoomProbe::RoomProbe() = default;
RoomProbe::~RoomProbe() = default;

void RoomProbe::set_resolution(int p_texels) { resolution = p_texels; }
int RoomProbe::get_resolution() const { return resolution; }

void RoomProbe::set_coarse_model_path(const NodePath &p_path) {
	coarse_model_path = p_path;
	update_configuration_warnings();
}

NodePath RoomProbe::get_coarse_model_path() const { return coarse_model_path; }
void RoomProbe::set_dense_slam_path(const NodePath &p_path) { dense_slam_path = p_path; }
NodePath RoomProbe::get_dense_slam_path() const { return dense_slam_path; }

void RoomProbe::set_update_mode(UpdateMode p_mode) {
	update_mode = p_mode;
	set_process(update_mode == UPDATE_ALWAYS && is_inside_tree());
}

RoomProbe::UpdateMode RoomProbe::get_update_mode() const { return update_mode; }

void RoomProbe::set_target_material(const Ref<ShaderMaterial> &p_material) {
	target_material = p_material;
	apply_to_material();
}

Ref<ShaderMaterial> RoomProbe::get_target_material() const { return target_material; }

void RoomProbe::set_material_parameter(const StringName &p_name) {
	material_parameter = p_name;
	apply_to_material();
}

StringName RoomProbe::get_material_parameter() const { return material_parameter; }

void RoomProbe::set_sh_parameter(const StringName &p_name) {
	sh_parameter = p_name;
	apply_to_material();
}

StringName RoomProbe::get_sh_parameter() const { return sh_parameter; }

void RoomProbe::_notification(int p_what) {
	if (p_what == NOTIFICATION_READY) {
		// A first map at once when the model is there; quietly none otherwise (see the warnings).
		const CoarseRoomModel *model = find_coarse_model();
		if (model != nullptr && model->get_room_mesh() != nullptr) {
			update_now();
		}
		set_process(update_mode == UPDATE_ALWAYS);
	}
}

void RoomProbe::_process(double p_delta) {
	(void)p_delta;
	if (update_mode == UPDATE_ALWAYS) {
		update_now();
	}
}

CoarseRoomModel *RoomProbe::find_coarse_model() const {
	if (coarse_model_path.is_empty() || !is_inside_tree()) {
		return nullptr;
	}
	return cast_to<CoarseRoomModel>(get_node_or_null(coarse_model_path));
}

bool RoomProbe::update_now() {
	ERR_FAIL_COND_V_MSG(resolution < 1 || resolution > 4096, false, "resolution must be 1..4096.");
	CoarseRoomModel *model = find_coarse_model();
	ERR_FAIL_COND_V_MSG(model == nullptr, false, "coarse_model does not lead to a CoarseRoomModel in the tree.");
	const RoomMesh *mesh = model->get_room_mesh();
	ERR_FAIL_COND_V_MSG(mesh == nullptr, false, "The CoarseRoomModel has no valid room.");
	if (!renderer || renderer_mesh_version != model->get_mesh_version()) {
		renderer = std::make_unique<CoarseCubemapRenderer>(*mesh);
		renderer_mesh_version = model->get_mesh_version();
	}
	// The room mesh is in the model's local frame; only its translation is accounted for.
	const Vector3 p = get_global_position() - model->get_global_position();
	const roomprobe::Cubemap map = renderer->render(model->get_texture(), glm::dvec3(p.x, p.y, p.z), resolution);
	ERR_FAIL_COND_V_MSG(!is_valid_cubemap(map), false, "Rendering the coarse model failed.");

	sh = project_sh(map);
	Array layers;
	Ref<Image> gpu_faces[6];
	const bool same_size = cubemap.is_valid() && cubemap->get_width() == resolution && cubemap->get_layers() == 6;
	for (int i = 0; i < 6; i++) {
		faces[i] = image_from_mat(map.faces[size_t(i)]);
		ERR_FAIL_COND_V(faces[i].is_null(), false);
		// Half floats with mipmaps for the GPU: rough materials read the coarser levels.
		Ref<Image> gpu = Image::create_from_data(resolution, resolution, false, Image::FORMAT_RGBF, faces[i]->get_data());
		gpu->convert(Image::FORMAT_RGBAH);
		gpu->generate_mipmaps();
		gpu_faces[i] = gpu;
		layers.push_back(gpu);
	}
	if (same_size) {
		for (int i = 0; i < 6; i++) {
			cubemap->update_layer(gpu_faces[i], i);
		}
	} else {
		cubemap.instantiate();
		const Error err = cubemap->create_from_images(layers);
		ERR_FAIL_COND_V_MSG(err != OK, false, "Could not create the Cubemap.");
	}
	has_map = true;
	apply_to_material();
	emit_signal("environment_map_updated");
	return true;
}

void RoomProbe::apply_to_material() {
	if (target_material.is_null() || !has_map) {
		return;
	}
	if (!String(material_parameter).is_empty()) {
		target_material->set_shader_parameter(material_parameter, cubemap);
	}
	if (!String(sh_parameter).is_empty()) {
		target_material->set_shader_parameter(sh_parameter, get_sh_coefficients());
	}
}

Ref<godot::Cubemap> RoomProbe::get_cubemap() const { return cubemap; }

Ref<Image> RoomProbe::get_face_image(int p_layer) const {
	ERR_FAIL_INDEX_V(p_layer, 6, Ref<Image>());
	return faces[p_layer];
}

PackedVector3Array RoomProbe::get_sh_coefficients() const {
	PackedVector3Array out;
	if (!has_map) {
		return out;
	}
	out.resize(SH_COEFFICIENTS);
	for (int i = 0; i < SH_COEFFICIENTS; i++) {
		out[i] = Vector3(real_t(sh[size_t(i)].x), real_t(sh[size_t(i)].y), real_t(sh[size_t(i)].z));
	}
	return out;
}

PackedStringArray RoomProbe::get_warnings() const {
	PackedStringArray warnings;
	if (coarse_model_path.is_empty()) {
		warnings.push_back("Set coarse_model to the CoarseRoomModel of the room.");
	} else if (is_inside_tree()) {
		const CoarseRoomModel *model = find_coarse_model();
		if (model == nullptr) {
			warnings.push_back("coarse_model does not lead to a CoarseRoomModel.");
		} else if (model->get_room_mesh() == nullptr) {
			warnings.push_back("The CoarseRoomModel has no valid room: no environment map.");
		}
	}
	warnings.push_back("Only the coarse model is rendered: the dense SLAM model is not implemented yet, and the coarse model's texture comes only from CoarseRoomModel.set_atlas_image() (fisheye texturing not wired yet).");
	warnings.push_back("The map reaches materials only through target_material (a ShaderMaterial, see shaders/): feeding a ReflectionProbe or the Environment is not supported yet.");
	return warnings;
}

void RoomProbe::_bind_methods() {
	ClassDB::bind_method(D_METHOD("get_warnings"), &RoomProbe::get_warnings);
	ClassDB::bind_method(D_METHOD("set_resolution", "texels"), &RoomProbe::set_resolution);
	ClassDB::bind_method(D_METHOD("get_resolution"), &RoomProbe::get_resolution);
	ClassDB::bind_method(D_METHOD("set_coarse_model", "path"), &RoomProbe::set_coarse_model_path);
	ClassDB::bind_method(D_METHOD("get_coarse_model"), &RoomProbe::get_coarse_model_path);
	ClassDB::bind_method(D_METHOD("set_dense_slam", "path"), &RoomProbe::set_dense_slam_path);
	ClassDB::bind_method(D_METHOD("get_dense_slam"), &RoomProbe::get_dense_slam_path);
	ClassDB::bind_method(D_METHOD("set_update_mode", "mode"), &RoomProbe::set_update_mode);
	ClassDB::bind_method(D_METHOD("get_update_mode"), &RoomProbe::get_update_mode);
	ClassDB::bind_method(D_METHOD("set_target_material", "material"), &RoomProbe::set_target_material);
	ClassDB::bind_method(D_METHOD("get_target_material"), &RoomProbe::get_target_material);
	ClassDB::bind_method(D_METHOD("set_material_parameter", "name"), &RoomProbe::set_material_parameter);
	ClassDB::bind_method(D_METHOD("get_material_parameter"), &RoomProbe::get_material_parameter);
	ClassDB::bind_method(D_METHOD("set_sh_parameter", "name"), &RoomProbe::set_sh_parameter);
	ClassDB::bind_method(D_METHOD("get_sh_parameter"), &RoomProbe::get_sh_parameter);
	ClassDB::bind_method(D_METHOD("update_now"), &RoomProbe::update_now);
	ClassDB::bind_method(D_METHOD("get_cubemap"), &RoomProbe::get_cubemap);
	ClassDB::bind_method(D_METHOD("get_face_image", "layer"), &RoomProbe::get_face_image);
	ClassDB::bind_method(D_METHOD("get_sh_coefficients"), &RoomProbe::get_sh_coefficients);

	ADD_PROPERTY(PropertyInfo(Variant::INT, "resolution", PROPERTY_HINT_ENUM, "64:64,128:128,256:256,512:512"), "set_resolution", "get_resolution");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "coarse_model", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "CoarseRoomModel"), "set_coarse_model", "get_coarse_model");
	ADD_PROPERTY(PropertyInfo(Variant::NODE_PATH, "dense_slam", PROPERTY_HINT_NODE_PATH_VALID_TYPES, "DenseSLAM"), "set_dense_slam", "get_dense_slam");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "update_mode", PROPERTY_HINT_ENUM, "Once,Always"), "set_update_mode", "get_update_mode");
	ADD_GROUP("Output", "");
	ADD_PROPERTY(PropertyInfo(Variant::OBJECT, "target_material", PROPERTY_HINT_RESOURCE_TYPE, "ShaderMaterial", PROPERTY_USAGE_DEFAULT, "ShaderMaterial"), "set_target_material", "get_target_material");
	ADD_PROPERTY(PropertyInfo(Variant::STRING_NAME, "material_parameter"), "set_material_parameter", "get_material_parameter");
	ADD_PROPERTY(PropertyInfo(Variant::STRING_NAME, "sh_parameter"), "set_sh_parameter", "get_sh_parameter");

	BIND_ENUM_CONSTANT(UPDATE_ONCE);
	BIND_ENUM_CONSTANT(UPDATE_ALWAYS);

	ADD_SIGNAL(MethodInfo("environment_map_updated"));
}

} // namespace roomprobe
