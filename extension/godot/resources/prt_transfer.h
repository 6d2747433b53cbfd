#pragma once
// PRTTransfer: a mesh's diffuse shadowed transfer (paper §4.8; the core's prt/prt_transfer.h) as
// a Godot resource, for shaders/prt_diffuse.gdshader. The transfer is an RGBAF image: vertex v's
// 25 coefficients are in 7 texels (the last one padded) at row v / 256, columns (v % 256) * 7 ..
// + 6, in the surface's own vertex order, so the shader reads them by VERTEX_ID. A cache key of
// the mesh and the settings is kept with it: bake() does nothing while they are unchanged.
// With an occluder, the mesh's vertices are shadowed by it too: a plane under an object gets the
// object's contact shadow (shaders/contact_shadow.gdshader).

#include <prt/prt_transfer.h>

#include <rp_godot/godot.h>

#include <cstdint>
#include <string>
#include <vector>

namespace roomprobe {

class PRTTransfer : public godot::Resource {
	GDCLASS(PRTTransfer, godot::Resource)

public:
	static constexpr int VERTICES_PER_ROW = 256;
	static constexpr int TEXELS_PER_VERTEX = 7;
	// The transfer vectors of p_vertices vertices back from a transfer image (the layout above).
	// "" or why the image cannot hold them.
	static std::string transfer_from_image(const godot::Ref<godot::Image> &p_image, int p_vertices, std::vector<TransferVector> *r_transfer);

	void set_mesh(const godot::Ref<godot::Mesh> &p_mesh);
	godot::Ref<godot::Mesh> get_mesh() const;
	void set_surface(int64_t p_surface);
	int get_surface() const;
	void set_samples_per_vertex(int64_t p_samples);
	int get_samples_per_vertex() const;
	void set_transfer(const godot::Ref<godot::Image> &p_transfer);
	godot::Ref<godot::Image> get_transfer() const;
	void set_cache_key(const godot::String &p_key);
	godot::String get_cache_key() const;
	void set_print_progress(bool p_on);
	bool get_print_progress() const;
	void set_occluder(const godot::Ref<godot::Mesh> &p_occluder);
	godot::Ref<godot::Mesh> get_occluder() const;
	void set_occluder_transform(const godot::Transform3D &p_transform);
	godot::Transform3D get_occluder_transform() const;

	// Bakes the transfer of the mesh's surface unless the cached one still matches; true on
	// success (also when nothing needed baking), false with get_last_error().
	bool bake();
	// Whether the transfer held matches the mesh and settings as they are now.
	bool is_baked() const;
	godot::Ref<godot::ImageTexture> get_transfer_texture() const;
	int get_vertex_count() const;
	// Seconds the last bake() took baking (0 when the cache was used), its rays, and why it failed.
	double get_last_bake_seconds() const;
	int64_t get_last_bake_rays() const;
	godot::String get_last_error() const;

protected:
	static void _bind_methods();

private:
	godot::String current_key() const; // "" when the mesh cannot be converted
	// The mesh and the occluder (placed by occluder_transform) as the bake takes them; "" or why not.
	std::string bake_inputs(PrtMesh *r_mesh, PrtMesh *r_occluder, bool *r_has_occluder) const;

	godot::Ref<godot::Mesh> mesh;
	int surface = 0;
	int samples_per_vertex = 4096;
	godot::Ref<godot::Image> transfer;
	godot::String cache_key;
	bool print_progress = false;
	godot::Ref<godot::Mesh> occluder;
	godot::Transform3D occluder_transform;
	double last_seconds = 0.0;
	int64_t last_rays = 0;
	godot::String last_error;
};

} // namespace roomprobe
