#include "sh_project_gpu.h"

#include <spirv/sh_project.h>

#include <cstring>

namespace roomprobe {

namespace {

constexpr uint32_t GROUP_SIZE = 64; // sh_project.comp's local_size_x
constexpr size_t ROW_FLOATS = 3 * SH_COEFFICIENTS;

} // namespace

std::unique_ptr<ShProjectorGpu> ShProjectorGpu::create(int p_size, std::shared_ptr<ComputeDevice> p_device, std::string *r_error) {
	if (p_size < 1 || !p_device) {
		*r_error = "no face size or no compute device";
		return nullptr;
	}
	std::unique_ptr<ShProjectorGpu> out(new ShProjectorGpu());
	out->compute = std::move(p_device);
	out->size = p_size;
	const ComputeDevice &device = *out->compute;
	const size_t texels = 6 * size_t(p_size) * size_t(p_size);
	const std::shared_ptr<const std::vector<float>> table = sh_texel_weights(p_size);
	out->kernel = device.make_kernel(spirv::sh_project, sizeof(spirv::sh_project) / sizeof(uint32_t), 3, sizeof(uint32_t), r_error, "sh_project");
	out->faces = device.make_buffer(texels * 3 * sizeof(float), GpuAccess::DeviceReads, r_error);
	out->weights = device.make_buffer(table->size() * sizeof(float), GpuAccess::DeviceReads, r_error);
	out->rows = device.make_buffer(6 * size_t(p_size) * ROW_FLOATS * sizeof(float), GpuAccess::HostReads, r_error);
	if (!out->kernel || !out->faces || !out->weights || !out->rows) {
		return nullptr;
	}
	std::memcpy(out->weights->data(), table->data(), table->size() * sizeof(float));
	return out;
}

bool ShProjectorGpu::project(const Cubemap &p_cubemap, ShCoefficients *r_sh, std::string *r_error) const {
	r_sh->fill(glm::dvec3(0.0));
	if (!is_valid_cubemap(p_cubemap)) {
		return true; // project_sh's zeros
	}
	const std::array<cv::Mat, 6> projected = sh_projection_faces(p_cubemap);
	if (projected[0].cols != size) {
		*r_error = "the cubemap's projected faces are not of the projector's size";
		return false;
	}
	const std::lock_guard<std::mutex> lock(mutex);
	const size_t face_floats = size_t(size) * size_t(size) * 3;
	for (size_t f = 0; f < 6; f++) {
		const cv::Mat face = projected[f].isContinuous() ? projected[f] : projected[f].clone();
		std::memcpy(static_cast<float *>(faces->data()) + f * face_floats, face.ptr<float>(0), face_floats * sizeof(float));
	}
	GpuDispatch dispatch;
	dispatch.kernel = kernel.get();
	dispatch.buffers = { faces.get(), weights.get(), rows.get() };
	const uint32_t face_size = uint32_t(size);
	dispatch.set_push(face_size);
	dispatch.groups_x = (6 * face_size + GROUP_SIZE - 1) / GROUP_SIZE;
	*r_error = compute->run({ dispatch });
	if (!r_error->empty()) {
		return false;
	}
	// The rows in double, in row order, as project_sh adds them.
	const float *row = static_cast<const float *>(rows->data());
	for (size_t r = 0; r < 6 * size_t(size); r++, row += ROW_FLOATS) {
		for (int i = 0; i < SH_COEFFICIENTS; i++) {
			(*r_sh)[size_t(i)] += glm::dvec3(row[i], row[SH_COEFFICIENTS + i], row[2 * SH_COEFFICIENTS + i]);
		}
	}
	return true;
}

} // namespace roomprobe
