#include "prt_transfer.h"

#include "../property_checks.h"

#include "../convert/mesh_convert.h"

#include <prt/prt_transfer.h>

#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <vector>

using namespace godot;

namespace roomprobe {

namespace {

String key_text(uint64_t p_key) {
	char text[24];
	std::snprintf(text, sizeof(text), "%016" PRIx64, p_key);
	return String(text);
}

TransferOptions options_with(int p_samples) {
	TransferOptions options;
	options.samples_per_vertex = p_samples;
	return options;
}

} // namespace

void PRTTransfer::set_mesh(const Ref<Mesh> &p_mesh) {
	mesh = p_mesh;
	emit_changed();
}

Ref<Mesh> PRTTransfer::get_mesh() const {
	return mesh;
}

void PRTTransfer::set_surface(int64_t p_surface) {
	surface = int(property_checks::clamped_int("PRTTransfer.surface", p_surface, 0, 255));
	emit_changed();
}

int PRTTransfer::get_surface() const {
	return surface;
}

void PRTTransfer::set_samples_per_vertex(int64_t p_samples) {
	// The range the inspector offers: 16 (a quick look) to 65536 (a reference).
	samples_per_vertex = int(property_checks::clamped_int("PRTTransfer.samples_per_vertex", p_samples, 16, 65536));
	emit_changed();
}

int PRTTransfer::get_samples_per_vertex() const {
	return samples_per_vertex;
}

void PRTTransfer::set_transfer(const Ref<Image> &p_transfer) {
	transfer = p_transfer;
	emit_changed();
}

Ref<Image> PRTTransfer::get_transfer() const {
	return transfer;
}

void PRTTransfer::set_cache_key(const String &p_key) {
	cache_key = p_key;
}

String PRTTransfer::get_cache_key() const {
	return cache_key;
}

void PRTTransfer::set_print_progress(bool p_on) {
	print_progress = p_on;
}

bool PRTTransfer::get_print_progress() const {
	return print_progress;
}

void PRTTransfer::set_occluder(const Ref<Mesh> &p_occluder) {
	occluder = p_occluder;
	emit_changed();
}

Ref<Mesh> PRTTransfer::get_occluder() const {
	return occluder;
}

void PRTTransfer::set_occluder_transform(const Transform3D &p_transform) {
	if (!property_checks::finite(p_transform)) {
		ERR_PRINT("PRTTransfer.occluder_transform must be finite (a number is NaN or infinite); left as it was");
		return;
	}
	occluder_transform = p_transform;
	emit_changed();
}

Transform3D PRTTransfer::get_occluder_transform() const {
	return occluder_transform;
}

std::string PRTTransfer::bake_inputs(PrtMesh *r_mesh, PrtMesh *r_occluder, bool *r_has_occluder) const {
	std::string problem = prt_mesh_from_surface(mesh, surface, r_mesh);
	*r_has_occluder = occluder.is_valid();
	if (!problem.empty() || !*r_has_occluder) {
		return problem;
	}
	problem = prt_mesh_from_surface(occluder, 0, r_occluder);
	if (!problem.empty()) {
		return "occluder: " + problem;
	}
	// Placed in the mesh's frame; its normals do not matter to shadows, so they are recomputed.
	for (glm::vec3 &p : r_occluder->positions) {
		const Vector3 placed = occluder_transform.xform(Vector3(p.x, p.y, p.z));
		p = glm::vec3(placed.x, placed.y, placed.z);
	}
	compute_vertex_normals(r_occluder);
	return std::string();
}

String PRTTransfer::current_key() const {
	PrtMesh triangles, blocker;
	bool has_occluder = false;
	if (!bake_inputs(&triangles, &blocker, &has_occluder).empty()) {
		return String();
	}
	return key_text(transfer_cache_key(triangles, has_occluder ? &blocker : nullptr, options_with(samples_per_vertex)));
}

bool PRTTransfer::is_baked() const {
	return transfer.is_valid() && !cache_key.is_empty() && cache_key == current_key();
}

bool PRTTransfer::bake() {
	last_seconds = 0.0;
	last_rays = 0;
	last_error = String();
	PrtMesh triangles, blocker;
	bool has_occluder = false;
	const std::string problem = bake_inputs(&triangles, &blocker, &has_occluder);
	if (!problem.empty()) {
		last_error = String(("PRTTransfer: " + problem).c_str());
		ERR_FAIL_COND_V_MSG(true, false, last_error);
	}
	TransferOptions options = options_with(samples_per_vertex);
	if (print_progress) {
		// From the bake's worker threads: a plain line to stdout (not Godot's print, which is the
		// main thread's).
		options.progress = [](size_t p_done, size_t p_total) {
			std::printf("\r  baking PRT transfer: %zu / %zu vertices", p_done, p_total);
			if (p_done == p_total) {
				std::printf("\n");
			}
			std::fflush(stdout);
		};
	}
	const PrtMesh *occluders = has_occluder ? &blocker : nullptr;
	const String key = key_text(transfer_cache_key(triangles, occluders, options));
	if (transfer.is_valid() && key == cache_key) {
		return true; // unchanged mesh and settings: the cached transfer stands
	}
	const TransferResult baked = bake_transfer(triangles, occluders, options);
	if (!baked.error.empty()) {
		last_error = String(("PRTTransfer: " + baked.error).c_str());
		ERR_FAIL_COND_V_MSG(true, false, last_error);
	}
	const int vertices = int(triangles.vertex_count());
	const int width = VERTICES_PER_ROW * TEXELS_PER_VERTEX;
	const int height = (vertices + VERTICES_PER_ROW - 1) / VERTICES_PER_ROW;
	std::vector<float> texels(size_t(width) * size_t(height) * 4, 0.0f);
	for (int v = 0; v < vertices; v++) {
		float *out = texels.data() + (size_t(v / VERTICES_PER_ROW) * width + size_t(v % VERTICES_PER_ROW) * TEXELS_PER_VERTEX) * 4;
		std::memcpy(out, baked.transfer[size_t(v)].data(), sizeof(float) * SH_COEFFICIENTS);
	}
	PackedByteArray bytes;
	bytes.resize(int64_t(texels.size() * sizeof(float)));
	std::memcpy(bytes.ptrw(), texels.data(), texels.size() * sizeof(float));
	transfer = Image::create_from_data(width, height, false, Image::FORMAT_RGBAF, bytes);
	cache_key = key;
	last_seconds = baked.seconds;
	last_rays = int64_t(baked.rays);
	emit_changed();
	return true;
}

std::string PRTTransfer::transfer_from_image(const Ref<Image> &p_image, int p_vertices, std::vector<TransferVector> *r_transfer) {
	r_transfer->clear();
	if (p_image.is_null() || p_image->get_format() != Image::FORMAT_RGBAF || p_image->get_width() != VERTICES_PER_ROW * TEXELS_PER_VERTEX) {
		return "not a PRTTransfer image (RGBAF, " + std::to_string(VERTICES_PER_ROW * TEXELS_PER_VERTEX) + " texels wide)";
	}
	const int rows = (p_vertices + VERTICES_PER_ROW - 1) / VERTICES_PER_ROW;
	if (p_vertices < 1 || p_image->get_height() < rows) {
		return "the image holds fewer vertices than the mesh's " + std::to_string(p_vertices);
	}
	const PackedByteArray bytes = p_image->get_data();
	const float *texels = reinterpret_cast<const float *>(bytes.ptr());
	const size_t width = size_t(VERTICES_PER_ROW) * TEXELS_PER_VERTEX;
	r_transfer->resize(size_t(p_vertices));
	for (int v = 0; v < p_vertices; v++) {
		const float *in = texels + (size_t(v / VERTICES_PER_ROW) * width + size_t(v % VERTICES_PER_ROW) * TEXELS_PER_VERTEX) * 4;
		std::memcpy((*r_transfer)[size_t(v)].data(), in, sizeof(float) * SH_COEFFICIENTS);
	}
	return "";
}

Ref<ImageTexture> PRTTransfer::get_transfer_texture() const {
	return transfer.is_valid() ? ImageTexture::create_from_image(transfer) : Ref<ImageTexture>();
}

int PRTTransfer::get_vertex_count() const {
	PrtMesh triangles;
	return prt_mesh_from_surface(mesh, surface, &triangles).empty() ? int(triangles.vertex_count()) : 0;
}

double PRTTransfer::get_last_bake_seconds() const {
	return last_seconds;
}

int64_t PRTTransfer::get_last_bake_rays() const {
	return last_rays;
}

String PRTTransfer::get_last_error() const {
	return last_error;
}

void PRTTransfer::_bind_methods() {
	ClassDB::bind_method(D_METHOD("set_mesh", "mesh"), &PRTTransfer::set_mesh);
	ClassDB::bind_method(D_METHOD("get_mesh"), &PRTTransfer::get_mesh);
	ClassDB::bind_method(D_METHOD("set_surface", "surface"), &PRTTransfer::set_surface);
	ClassDB::bind_method(D_METHOD("get_surface"), &PRTTransfer::get_surface);
	ClassDB::bind_method(D_METHOD("set_samples_per_vertex", "samples"), &PRTTransfer::set_samples_per_vertex);
	ClassDB::bind_method(D_METHOD("get_samples_per_vertex"), &PRTTransfer::get_samples_per_vertex);
	ClassDB::bind_method(D_METHOD("set_transfer", "transfer"), &PRTTransfer::set_transfer);
	ClassDB::bind_method(D_METHOD("get_transfer"), &PRTTransfer::get_transfer);
	ClassDB::bind_method(D_METHOD("set_cache_key", "key"), &PRTTransfer::set_cache_key);
	ClassDB::bind_method(D_METHOD("get_cache_key"), &PRTTransfer::get_cache_key);
	ClassDB::bind_method(D_METHOD("set_print_progress", "on"), &PRTTransfer::set_print_progress);
	ClassDB::bind_method(D_METHOD("get_print_progress"), &PRTTransfer::get_print_progress);
	ClassDB::bind_method(D_METHOD("set_occluder", "occluder"), &PRTTransfer::set_occluder);
	ClassDB::bind_method(D_METHOD("get_occluder"), &PRTTransfer::get_occluder);
	ClassDB::bind_method(D_METHOD("set_occluder_transform", "transform"), &PRTTransfer::set_occluder_transform);
	ClassDB::bind_method(D_METHOD("get_occluder_transform"), &PRTTransfer::get_occluder_transform);
	ClassDB::bind_method(D_METHOD("bake"), &PRTTransfer::bake);
	ClassDB::bind_method(D_METHOD("is_baked"), &PRTTransfer::is_baked);
	ClassDB::bind_method(D_METHOD("get_transfer_texture"), &PRTTransfer::get_transfer_texture);
	ClassDB::bind_method(D_METHOD("get_vertex_count"), &PRTTransfer::get_vertex_count);
	ClassDB::bind_method(D_METHOD("get_last_bake_seconds"), &PRTTransfer::get_last_bake_seconds);
	ClassDB::bind_method(D_METHOD("get_last_bake_rays"), &PRTTransfer::get_last_bake_rays);
	ClassDB::bind_method(D_METHOD("get_last_error"), &PRTTransfer::get_last_error);
	ADD_PROPERTY(PropertyInfo(Variant::OBJECT, "mesh", PROPERTY_HINT_RESOURCE_TYPE, "Mesh", PROPERTY_USAGE_DEFAULT, "Mesh"), "set_mesh", "get_mesh");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "surface", PROPERTY_HINT_RANGE, "0,255,1"), "set_surface", "get_surface");
	ADD_PROPERTY(PropertyInfo(Variant::OBJECT, "occluder", PROPERTY_HINT_RESOURCE_TYPE, "Mesh", PROPERTY_USAGE_DEFAULT, "Mesh"), "set_occluder", "get_occluder");
	ADD_PROPERTY(PropertyInfo(Variant::TRANSFORM3D, "occluder_transform"), "set_occluder_transform", "get_occluder_transform");
	ADD_PROPERTY(PropertyInfo(Variant::INT, "samples_per_vertex", PROPERTY_HINT_RANGE, "16,65536,1"), "set_samples_per_vertex", "get_samples_per_vertex");
	ADD_PROPERTY(PropertyInfo(Variant::BOOL, "print_progress"), "set_print_progress", "get_print_progress");
	ADD_PROPERTY(PropertyInfo(Variant::OBJECT, "transfer", PROPERTY_HINT_RESOURCE_TYPE, "Image", PROPERTY_USAGE_STORAGE, "Image"), "set_transfer", "get_transfer");
	ADD_PROPERTY(PropertyInfo(Variant::STRING, "cache_key", PROPERTY_HINT_NONE, "", PROPERTY_USAGE_STORAGE), "set_cache_key", "get_cache_key");
}

} // namespace roomprobe
