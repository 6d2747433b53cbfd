#include "export.h"
#include <io/image_codec.h>
#include <io/exr_write.h>
#include <io/input_path.h>

#include <math/srgb.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <filesystem>

namespace roomprobe {

namespace {

const char *const k_channels[3] = { "R", "G", "B" };

} // namespace

std::string write_cubemap_exr(const std::string &p_path, const Cubemap &p_cubemap) {
	if (!is_valid_cubemap(p_cubemap)) {
		return p_path + ": not written, the cubemap is empty or its faces are not square CV_32FC3 of its size";
	}
	const cv::Mat strip = cubemap_faces_to_strip(p_cubemap.faces);
	if (strip.empty() || !strip.isContinuous()) {
		return p_path + ": not written, the faces do not form a strip";
	}
	Imf::Header header(strip.cols, strip.rows);
	header.compression() = Imf::ZIP_COMPRESSION;
	for (const char *name : k_channels) {
		header.channels().insert(name, Imf::Channel(Imf::FLOAT));
	}
	Imf::FrameBuffer buffer;
	char *base = const_cast<char *>(reinterpret_cast<const char *>(strip.ptr<float>()));
	const size_t x_stride = 3 * sizeof(float);
	const size_t y_stride = x_stride * size_t(strip.cols);
	for (int c = 0; c < 3; c++) {
		buffer.insert(k_channels[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), x_stride, y_stride));
	}
	return write_exr(p_path, header, buffer, strip.rows);
}

std::string read_cubemap_exr(const std::string &p_path, Cubemap *r_cubemap) {
	const std::string not_a_file = input_file_problem(p_path);
	if (!not_a_file.empty()) {
		return not_a_file;
	}
	cv::Mat strip;
	try {
		Imf::InputFile file(p_path.c_str());
		for (const char *name : k_channels) {
			if (file.header().channels().findChannel(name) == nullptr) {
				return p_path + ": no '" + name + "' channel";
			}
		}
		const Imath::Box2i window = file.header().dataWindow();
		const int width = window.max.x - window.min.x + 1;
		const int height = window.max.y - window.min.y + 1;
		if (width <= 0 || height != 6 * width) {
			return p_path + ": " + std::to_string(width) + " x " + std::to_string(height) + " is not an N x 6N cubemap strip";
		}
		strip = cv::Mat(height, width, CV_32FC3);
		Imf::FrameBuffer buffer;
		for (int c = 0; c < 3; c++) {
			buffer.insert(k_channels[c], Imf::Slice::Make(Imf::FLOAT, strip.ptr<float>() + c, window, 3 * sizeof(float), 3 * sizeof(float) * size_t(width)));
		}
		file.setFrameBuffer(buffer);
		file.readPixels(window.min.y, window.max.y);
	} catch (const std::exception &e) {
		return p_path + ": " + e.what();
	}
	r_cubemap->size = strip.cols;
	r_cubemap->faces = cubemap_strip_to_faces(strip);
	return std::string();
}

uint8_t tone_map_srgb8(float p_linear) {
	const double c = std::isfinite(p_linear) ? std::clamp(double(p_linear), 0.0, 1.0) : 0.0;
	const double encoded = srgb_encode(c);
	return uint8_t(std::lround(std::clamp(encoded, 0.0, 1.0) * 255.0));
}

void cubemap_net_cell(int p_face, int *r_column, int *r_row) {
	static const int columns[6] = { 2, 0, 1, 1, 1, 3 };
	static const int rows[6] = { 1, 1, 0, 2, 1, 1 };
	const int face = p_face >= 0 && p_face < 6 ? p_face : 0;
	*r_column = columns[face];
	*r_row = rows[face];
}

cv::Mat cubemap_net_image(const Cubemap &p_cubemap) {
	if (!is_valid_cubemap(p_cubemap)) {
		return cv::Mat();
	}
	const int n = p_cubemap.size;
	cv::Mat net = cv::Mat::zeros(3 * n, 4 * n, CV_8UC3);
	for (int face = 0; face < 6; face++) {
		int column = 0;
		int row = 0;
		cubemap_net_cell(face, &column, &row);
		const cv::Mat &source = p_cubemap.faces[size_t(face)];
		for (int v = 0; v < n; v++) {
			const cv::Vec3f *in = source.ptr<cv::Vec3f>(v);
			cv::Vec3b *out = net.ptr<cv::Vec3b>(row * n + v) + column * n;
			for (int u = 0; u < n; u++) {
				out[u] = cv::Vec3b(tone_map_srgb8(in[u][0]), tone_map_srgb8(in[u][1]), tone_map_srgb8(in[u][2]));
			}
		}
	}
	return net;
}

std::string write_cubemap_png_net(const std::string &p_path, const Cubemap &p_cubemap) {
	const cv::Mat net = cubemap_net_image(p_cubemap);
	if (net.empty()) {
		return p_path + ": not written, the cubemap is empty or its faces are not square CV_32FC3 of its size";
	}
	cv::Mat bgr;
	cv::cvtColor(net, bgr, cv::COLOR_RGB2BGR);
	return png_write(p_path, bgr);
}

} // namespace roomprobe
