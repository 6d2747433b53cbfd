#include "bench_decode.h"

#include <io/image_codec.h>
#include <io/opencv.h>
#include <io/raw_frame.h>
#include <recording/recording_reader.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace roomprobe::bench {

namespace {

namespace fs = std::filesystem;

double now_ms() {
	return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Samples {
	std::vector<double> values;
	void add(double p_value) { values.push_back(p_value); }
	double median() const {
		if (values.empty()) {
			return 0.0;
		}
		std::vector<double> sorted = values;
		std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
		return sorted[sorted.size() / 2];
	}
	double mean() const {
		double sum = 0.0;
		for (double v : values) {
			sum += v;
		}
		return values.empty() ? 0.0 : sum / double(values.size());
	}
};

uint64_t file_bytes(const std::string &p_path) {
	std::error_code ec;
	const uintmax_t size = fs::file_size(p_path, ec);
	return ec ? 0 : uint64_t(size);
}

std::string join(const std::string &p_folder, const std::string &p_relative) {
	return (fs::path(p_folder) / p_relative).string();
}

bool same_samples(const cv::Mat &p_a, const cv::Mat &p_b) {
	if (p_a.type() != p_b.type() || p_a.size() != p_b.size()) {
		return false;
	}
	const size_t row_bytes = size_t(p_a.cols) * p_a.elemSize();
	for (int y = 0; y < p_a.rows; y++) {
		if (std::memcmp(p_a.ptr(y), p_b.ptr(y), row_bytes) != 0) {
			return false;
		}
	}
	return true;
}

// A stored frame file's samples as they are in the file: a depth PNG or raw frame as 16 bits.
std::string decode_stored(const std::string &p_path, cv::Mat *r_image) {
	std::vector<uint8_t> bytes;
	std::string error = read_file_bytes(p_path, &bytes);
	if (error.empty()) {
		error = raw_frame_signature(bytes.data(), bytes.size()) ? raw_frame_decode(bytes.data(), bytes.size(), r_image)
																: png_decode(bytes.data(), bytes.size(), r_image);
	}
	return error.empty() ? error : p_path + ": " + error;
}

struct CodecFigures {
	Samples encode_ms;
	Samples decode_ms;
	uint64_t bytes = 0; // over one pass
	size_t frames = 0; // in one pass
	bool exact = true;
};

struct Codec {
	std::string name; // png, zstd1, ...
	int level = 0; // zstd's; PNG: unused
	bool png = false;
};

// Encodes and decodes every frame p_repeats times; colour frames are R, G, B (PNG swaps them to
// B, G, R and back, as the recording's writer and reader do).
std::string run_codec(const Codec &p_codec, const std::vector<cv::Mat> &p_frames, int p_repeats, CodecFigures *r_figures) {
	for (int pass = 0; pass < p_repeats; pass++) {
		for (const cv::Mat &frame : p_frames) {
			std::vector<uint8_t> bytes;
			cv::Mat decoded;
			std::string error;
			const double start = now_ms();
			if (p_codec.png) {
				cv::Mat bgr; // a new image: converting into one that shares the frame's pixels would swap the frame itself
				if (frame.channels() == 3) {
					cv::cvtColor(frame, bgr, cv::COLOR_RGB2BGR);
				} else {
					bgr = frame;
				}
				error = png_encode(bgr, &bytes);
			} else {
				error = raw_frame_encode(frame, p_codec.level, &bytes);
			}
			const double encoded = now_ms();
			if (error.empty() && p_codec.png) {
				error = png_decode(bytes.data(), bytes.size(), &decoded);
				if (error.empty() && decoded.channels() == 3) {
					cv::cvtColor(decoded, decoded, cv::COLOR_BGR2RGB);
				}
			} else if (error.empty()) {
				error = raw_frame_decode(bytes.data(), bytes.size(), &decoded);
			}
			const double done = now_ms();
			if (!error.empty()) {
				return p_codec.name + ": " + error;
			}
			r_figures->encode_ms.add(encoded - start);
			r_figures->decode_ms.add(done - encoded);
			if (pass == 0) {
				r_figures->bytes += bytes.size();
				r_figures->frames++;
				r_figures->exact = r_figures->exact && same_samples(frame, decoded);
			}
		}
	}
	return "";
}

struct Stream {
	const char *name; // rgb, depth, fisheye
	std::vector<cv::Mat> frames;
};

std::string describe(const cv::Mat &p_image) {
	const char *depth = p_image.depth() == CV_8U ? "8-bit" : p_image.depth() == CV_16U ? "16-bit" : p_image.depth() == CV_16F ? "half" : "float";
	return std::to_string(p_image.cols) + "x" + std::to_string(p_image.rows) + " " + depth + " " + std::to_string(p_image.channels()) + "-channel";
}

// How the recording's RGB-D frames are stored: zstd, png, ... ("none" without RGB-D frames).
std::string stored_format(const RecordingReader &p_reader, size_t p_rgbd_count) {
	if (p_rgbd_count == 0) {
		return "none";
	}
	const std::string extension = fs::path(p_reader.get_rgbd_ref(0).rgb.path).extension().string();
	return extension == ".zst" ? "zstd" : extension.empty() ? "unknown" : extension.substr(1);
}

// Part 1's figures: the files' bytes over one pass and the timed reads.
struct StoredFigures {
	uint64_t rgbd_bytes = 0, fisheye_bytes = 0;
	bool fisheye_hdr = false;
	Samples read_rgbd, read_fisheye;
};

double bytes_per_frame(uint64_t p_bytes, size_t p_frames) {
	return p_frames ? double(p_bytes) / double(p_frames) : 0.0;
}

// The warm-up pass: every frame read once, kept in r_streams (rgb, depth as stored, fisheye) for
// part 2, and the files' bytes counted; false (said) when one fails.
bool keep_frames(const RecordingReader &p_reader, size_t p_rgbd_count, size_t p_fisheye_count, Stream *r_streams, StoredFigures *r_figures) {
	const std::string folder = p_reader.get_folder();
	for (size_t i = 0; i < p_rgbd_count; i++) {
		const RgbdFrameResult frame = p_reader.read_rgbd(i);
		if (!frame.ok) {
			std::fprintf(stderr, "roomprobe_bench: %s\n", frame.error.c_str());
			return false;
		}
		const RgbdFrameRef &ref = p_reader.get_rgbd_ref(i);
		cv::Mat raw_depth;
		const std::string error = decode_stored(join(folder, ref.depth.path), &raw_depth);
		if (!error.empty()) {
			std::fprintf(stderr, "roomprobe_bench: %s\n", error.c_str());
			return false;
		}
		r_streams[0].frames.push_back(frame.frame.rgb);
		r_streams[1].frames.push_back(raw_depth);
		r_figures->rgbd_bytes += file_bytes(join(folder, ref.rgb.path)) + file_bytes(join(folder, ref.depth.path));
	}
	for (size_t i = 0; i < p_fisheye_count; i++) {
		const FisheyeFrameResult frame = p_reader.read_fisheye(i);
		if (!frame.ok) {
			std::fprintf(stderr, "roomprobe_bench: %s\n", frame.error.c_str());
			return false;
		}
		cv::Mat image = frame.frame.image;
		if (frame.frame.hdr) {
			r_figures->fisheye_hdr = true;
			image.convertTo(image, CV_16F); // as a half-float raw frame would hold it
		}
		r_streams[2].frames.push_back(image);
		r_figures->fisheye_bytes += file_bytes(join(folder, p_reader.get_fisheye_ref(i).path));
	}
	return true;
}

// p_repeats timed passes of reading every frame through the reader; false (said) when a frame no
// longer reads.
bool time_reads(const RecordingReader &p_reader, size_t p_rgbd_count, size_t p_fisheye_count, int p_repeats, StoredFigures *r_figures) {
	for (int pass = 0; pass < p_repeats; pass++) {
		for (size_t i = 0; i < p_rgbd_count; i++) {
			const double start = now_ms();
			const bool ok = p_reader.read_rgbd(i).ok;
			r_figures->read_rgbd.add(now_ms() - start);
			if (!ok) {
				std::fprintf(stderr, "roomprobe_bench: RGB-D frame %zu no longer reads\n", i);
				return false;
			}
		}
		for (size_t i = 0; i < p_fisheye_count; i++) {
			const double start = now_ms();
			const bool ok = p_reader.read_fisheye(i).ok;
			r_figures->read_fisheye.add(now_ms() - start);
			if (!ok) {
				std::fprintf(stderr, "roomprobe_bench: fisheye frame %zu no longer reads\n", i);
				return false;
			}
		}
	}
	return true;
}

// Part 2: each stream through each codec, a table row each; the summary's keys onto *r_summary and
// whether every frame round-tripped into *r_all_exact. False (said) when a codec fails.
bool compare_codecs(const Stream (&p_streams)[3], const DecodeBenchOptions &p_options, std::string *r_summary, bool *r_all_exact) {
	std::vector<Codec> codecs = { { "png", 0, true } };
	for (int level : p_options.levels) {
		codecs.push_back({ level < 0 ? "zstd_neg" + std::to_string(-level) : "zstd" + std::to_string(level), level, false });
	}
	std::printf("each encoding on the same frames, in memory (median per frame; PNG includes the R, G, B <-> B, G, R swap of colour):\n");
	std::printf("  %-10s %-8s %-30s %12s %8s %11s %11s %s\n", "encoding", "stream", "frames", "bytes/frame", "ratio", "encode_ms", "decode_ms", "bit-exact");
	for (const Stream &stream : p_streams) {
		if (stream.frames.empty()) {
			continue;
		}
		const cv::Mat &first = stream.frames.front();
		const double raw_bytes = double(first.total() * first.elemSize());
		for (const Codec &codec : codecs) {
			if (codec.png && first.depth() == CV_16F) {
				std::printf("  %-10s %-8s %-30s (PNG holds no half floats: the HDR frames' EXR cost is read_fisheye above)\n", codec.name.c_str(), stream.name,
						describe(first).c_str());
				continue;
			}
			CodecFigures figures;
			const std::string error = run_codec(codec, stream.frames, p_options.repeats, &figures);
			if (!error.empty()) {
				std::fprintf(stderr, "roomprobe_bench: %s frame: %s\n", stream.name, error.c_str());
				return false;
			}
			const double per_frame = double(figures.bytes) / double(std::max<size_t>(figures.frames, 1));
			std::printf("  %-10s %-8s %-30s %12.0f %7.2fx %11.2f %11.2f %s\n", codec.name.c_str(), stream.name,
					(describe(first) + " x" + std::to_string(stream.frames.size())).c_str(), per_frame, raw_bytes / per_frame, figures.encode_ms.median(),
					figures.decode_ms.median(), figures.exact ? "yes" : "NO");
			*r_all_exact = *r_all_exact && figures.exact;
			char keys[256];
			std::snprintf(keys, sizeof(keys), " %s_%s_bytes=%.0f %s_%s_encode_ms=%.2f %s_%s_decode_ms=%.2f", codec.name.c_str(), stream.name, per_frame,
					codec.name.c_str(), stream.name, figures.encode_ms.median(), codec.name.c_str(), stream.name, figures.decode_ms.median());
			*r_summary += keys;
		}
	}
	return true;
}

} // namespace

int bench_decode(const DecodeBenchOptions &p_options) {
	RecordingReader reader;
	const RecordingStatus opened = reader.open(p_options.recording);
	if (!opened.ok) {
		std::fprintf(stderr, "roomprobe_bench: %s\n", opened.error.c_str());
		return 1;
	}
	const size_t limit = p_options.frames < 0 ? SIZE_MAX : size_t(p_options.frames);
	const size_t rgbd_count = std::min(reader.rgbd_count(), limit);
	const size_t fisheye_count = std::min(reader.fisheye_count(), limit);
	const std::string format = stored_format(reader, rgbd_count);
	std::printf("roomprobe_bench decode --recording %s\n", p_options.recording.c_str());
	std::printf("  %zu RGB-D frames, %zu fisheye frames (of %zu, %zu); RGB-D frames stored as %s; %d timed passes after one warm-up\n",
			rgbd_count, fisheye_count, reader.rgbd_count(), reader.fisheye_count(), format.c_str(), p_options.repeats);

	// 1. As stored, through the reader. The warm-up pass keeps the frames for part 2.
	Stream streams[3] = { { "rgb", {} }, { "depth", {} }, { "fisheye", {} } };
	StoredFigures stored;
	if (!keep_frames(reader, rgbd_count, fisheye_count, streams, &stored) || !time_reads(reader, rgbd_count, fisheye_count, p_options.repeats, &stored)) {
		return 1;
	}
	const double rgbd_bytes_per_frame = bytes_per_frame(stored.rgbd_bytes, rgbd_count);
	const double fisheye_bytes_per_frame = bytes_per_frame(stored.fisheye_bytes, fisheye_count);
	const Samples &read_rgbd = stored.read_rgbd, &read_fisheye = stored.read_fisheye;
	std::printf("as stored, through RecordingReader (file read, decode, checks, conversion to the frame's types):\n");
	std::printf("  read_rgbd     %8.2f ms median  %8.2f ms mean   %10.0f bytes per frame (RGB and depth files)\n", read_rgbd.median(), read_rgbd.mean(),
			rgbd_bytes_per_frame);
	std::printf("  read_fisheye  %8.2f ms median  %8.2f ms mean   %10.0f bytes per frame%s\n", read_fisheye.median(), read_fisheye.mean(),
			fisheye_bytes_per_frame, stored.fisheye_hdr ? " (HDR)" : "");

	// 2. Each encoding on the same frames, in memory.
	std::string summary;
	bool all_exact = true;
	if (!compare_codecs(streams, p_options, &summary, &all_exact)) {
		return 1;
	}
	std::printf("summary: mode=decode format=%s rgbd_frames=%zu fisheye_frames=%zu read_rgbd_ms_p50=%.2f read_fisheye_ms_p50=%.2f "
				"rgbd_bytes_per_frame=%.0f fisheye_bytes_per_frame=%.0f bit_exact=%d%s\n",
			format.c_str(), rgbd_count, fisheye_count, read_rgbd.median(), read_fisheye.median(), rgbd_bytes_per_frame, fisheye_bytes_per_frame,
			all_exact ? 1 : 0, summary.c_str());
	return all_exact ? 0 : 1;
}

} // namespace roomprobe::bench
