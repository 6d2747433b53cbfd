#include "icp_reduce_gpu.h"

#include <spirv/icp_reduce.h>

#include <cmath>
#include <cstdint>
#include <cstring>

namespace roomprobe {

namespace {

constexpr int MODEL_FLOATS = 12; // per model pixel, its Model

// icp_reduce.comp's Params, std430.
struct Params {
	float rotation[12];
	float translation[4];
	float model_rotation[12];
	float model_translation[4];
	float camera[4];
	int32_t model_size[4];
	int32_t frame[4];
	float thresholds[4];
	float noise[4];
};
static_assert(sizeof(Params) == 52 * sizeof(float));

void put_matrix(const glm::mat3 &p_matrix, float (&r_columns)[12]) {
	for (int c = 0; c < 3; c++) {
		for (int r = 0; r < 3; r++) {
			r_columns[4 * c + r] = p_matrix[c][r];
		}
		r_columns[4 * c + 3] = 0.0f;
	}
}

void put_vector(const glm::vec3 &p_vector, float (&r_vector)[4]) {
	r_vector[0] = p_vector.x;
	r_vector[1] = p_vector.y;
	r_vector[2] = p_vector.z;
	r_vector[3] = 0.0f;
}

} // namespace

std::unique_ptr<IcpReducerGpu> IcpReducerGpu::create(std::shared_ptr<ComputeDevice> p_device, std::string *r_error) {
	if (!p_device) {
		*r_error = "no compute device";
		return nullptr;
	}
	std::unique_ptr<IcpReducerGpu> out(new IcpReducerGpu());
	out->compute = std::move(p_device);
	out->kernel = out->compute->make_kernel(spirv::icp_reduce, sizeof(spirv::icp_reduce) / sizeof(uint32_t), 4, 0, r_error, "icp_reduce");
	if (!out->kernel || !out->ensure(&out->params, sizeof(Params), GpuAccess::DeviceReads, r_error)) {
		return nullptr;
	}
	return out;
}

void IcpReducerGpu::set_failed(const std::string &p_reason) {
	const std::lock_guard<std::mutex> lock(failure_mutex);
	failure_reason = p_reason;
	failed = true;
}

std::string IcpReducerGpu::failure() const {
	const std::lock_guard<std::mutex> lock(failure_mutex);
	return failure_reason;
}

bool IcpReducerGpu::ensure(std::unique_ptr<GpuBuffer> *r_buffer, size_t p_bytes, GpuAccess p_access, std::string *r_error) const {
	return compute->ensure_buffer(r_buffer, p_bytes, p_access, r_error);
}

size_t IcpReducerGpu::plan_levels(const PinholeIntrinsics &p_camera, int p_levels, int p_finest_stride) {
	levels.assign(size_t(p_levels), Level());
	size_t floats = 0;
	for (int l = 0; l < p_levels; l++) {
		const int stride = l == 0 ? p_finest_stride : 1;
		const PinholeIntrinsics camera = p_camera.level(l);
		Level &level = levels[size_t(l)];
		level.cols = (camera.width + stride - 1) / stride;
		level.rows = (camera.height + stride - 1) / stride;
		level.first_float = floats;
		floats += size_t(level.cols) * size_t(level.rows) * FRAME_FLOATS;
	}
	return floats;
}

bool IcpReducerGpu::set_frame(const FramePyramid &p_frame, int p_levels, int p_finest_stride, std::string *r_error) {
	const size_t floats = plan_levels(p_frame.cameras[0], p_levels, p_finest_stride);
	if (!ensure(&frame, floats * sizeof(float), GpuAccess::DeviceReads, r_error)) {
		return false;
	}
	float *out = static_cast<float *>(frame->data());
	for (int l = 0; l < p_levels; l++) {
		const int stride = l == 0 ? p_finest_stride : 1;
		const Level &level = levels[size_t(l)];
		const cv::Mat *intensity = p_frame.intensity.empty() ? nullptr : &p_frame.intensity[size_t(l)];
		float *pixel = out + level.first_float;
		for (int r = 0; r < level.rows; r++) {
			const cv::Vec3f *v = p_frame.vertices[size_t(l)].ptr<cv::Vec3f>(r * stride);
			const cv::Vec3f *n = p_frame.normals[size_t(l)].ptr<cv::Vec3f>(r * stride);
			const float *i = intensity != nullptr ? intensity->ptr<float>(r * stride) : nullptr;
			for (int c = 0; c < level.cols; c++, pixel += FRAME_FLOATS) {
				const int x = c * stride;
				const bool geometry = v[x][2] > 0.0f && !std::isnan(n[x][0]);
				const bool has_intensity = i != nullptr && !std::isnan(i[x]);
				std::memset(pixel, 0, FRAME_FLOATS * sizeof(float));
				if (geometry) {
					for (int k = 0; k < 3; k++) {
						pixel[k] = v[x][k];
						pixel[3 + k] = n[x][k];
					}
					pixel[6] = has_intensity ? i[x] : 0.0f;
					pixel[7] = has_intensity ? 3.0f : 1.0f;
				}
			}
		}
	}
	return true;
}

std::vector<float> IcpReducerGpu::frame_floats() const {
	if (!frame || levels.empty()) {
		return {};
	}
	const Level &last = levels.back();
	const size_t floats = last.first_float + size_t(last.cols) * size_t(last.rows) * FRAME_FLOATS;
	const float *data = static_cast<const float *>(frame->data());
	return std::vector<float>(data, data + floats);
}

bool IcpReducerGpu::set_model(const IcpModelView &p_model, std::string *r_error) {
	const int w = p_model.camera.width, h = p_model.camera.height;
	if (!ensure(&model, size_t(w) * size_t(h) * MODEL_FLOATS * sizeof(float), GpuAccess::DeviceReads, r_error)) {
		return false;
	}
	model_colour = p_model.intensity != nullptr;
	model_camera = p_model.camera;
	model_rotation = p_model.camera_from_world_rotation;
	model_translation = p_model.camera_from_world_translation;
	float *pixel = static_cast<float *>(model->data());
	for (int y = 0; y < h; y++) {
		const float *points = p_model.points + size_t(y) * p_model.stride;
		const float *normals = p_model.normals + size_t(y) * p_model.stride;
		const size_t colour_row = size_t(y) * p_model.intensity_stride;
		for (int x = 0; x < w; x++, pixel += MODEL_FLOATS) {
			std::memset(pixel, 0, MODEL_FLOATS * sizeof(float));
			const float *point = points + 3 * x, *normal = normals + 3 * x;
			if (!std::isnan(point[0]) && !std::isnan(normal[0])) {
				for (int k = 0; k < 3; k++) {
					pixel[k] = point[k];
					pixel[4 + k] = normal[k];
				}
				pixel[3] = 1.0f;
			}
			if (model_colour) {
				const float i = p_model.intensity[colour_row + size_t(x)];
				const float gx = p_model.gradient_x[colour_row + size_t(x)], gy = p_model.gradient_y[colour_row + size_t(x)];
				if (!std::isnan(i) && !std::isnan(gx) && !std::isnan(gy)) {
					pixel[8] = i;
					pixel[9] = gx;
					pixel[10] = gy;
					pixel[11] = 1.0f;
				}
			}
		}
	}
	return true;
}

bool IcpReducerGpu::reduce(int p_level, const IcpKernelParams &p_params, const float **r_rows, int *r_row_count, std::string *r_error) {
	if (p_level < 0 || p_level >= int(levels.size()) || !model || model_camera.width == 0) {
		*r_error = "no frame or model for level " + std::to_string(p_level);
		return false;
	}
	const Level &level = levels[size_t(p_level)];
	if (!ensure(&rows, size_t(level.rows) * ROW_FLOATS * sizeof(float), GpuAccess::HostReads, r_error)) {
		return false;
	}
	Params values{};
	put_matrix(p_params.rotation, values.rotation);
	put_vector(p_params.translation, values.translation);
	put_matrix(model_rotation, values.model_rotation);
	put_vector(model_translation, values.model_translation);
	const float camera_values[4] = { model_camera.fx, model_camera.fy, model_camera.cx, model_camera.cy };
	std::memcpy(values.camera, camera_values, sizeof(camera_values));
	const int32_t model_size[4] = { model_camera.width, model_camera.height, model_colour ? 1 : 0, 0 };
	std::memcpy(values.model_size, model_size, sizeof(model_size));
	const int32_t frame_values[4] = { level.cols, level.rows, int32_t(level.first_float), 0 };
	std::memcpy(values.frame, frame_values, sizeof(frame_values));
	const float thresholds[4] = { p_params.max_distance_m, p_params.min_normal_cos, p_params.colour_weight, p_params.max_colour_difference };
	std::memcpy(values.thresholds, thresholds, sizeof(thresholds));
	const float noise[4] = { p_params.noise_a_m, p_params.noise_b_per_m2, p_params.noise_c_m, p_params.noise_reference_sigma_m };
	std::memcpy(values.noise, noise, sizeof(noise));
	std::memcpy(params->data(), &values, sizeof(values));

	GpuDispatch dispatch;
	dispatch.kernel = kernel.get();
	dispatch.buffers = { params.get(), frame.get(), model.get(), rows.get() };
	dispatch.groups_x = uint32_t(level.rows);
	*r_error = compute->run({ dispatch });
	if (!r_error->empty()) {
		return false;
	}
	*r_rows = static_cast<const float *>(rows->data());
	*r_row_count = level.rows;
	return true;
}

} // namespace roomprobe
