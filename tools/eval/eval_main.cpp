// roomprobe_eval: scores environment-map estimates against a recording's ground-truth cubemaps
// (paper §5.3): the §5.3 baseline, the coarse model without / with inpainting and with the two
// lighting compensations, and the dense model over it, with true poses and tracked by SLAM
// (eval/evaluate.h).
//
// roomprobe_eval --recording DIR [--out DIR [--force]] [--cubemap-size N] [--per-frame] [--texel-size M]
//                [--max-cubemaps K] [--no-dense] [--quiet] [--budget] [--rgb-texture] [--no-fisheye]
//                [--dense-range M] [--backend cpu|vulkan|auto] [--lighting-field PRIOR] [--dense-scale N]
// roomprobe_eval --compare A.exr B.exr   (two cubemaps: B against A, e.g. one backend's map against the other's)
// Maps already in --out are kept, the evaluation refused, unless --force (as every tool's outputs).

#include <envmap/export.h>
#include <eval/evaluate.h>
#include <eval/metrics.h>

#include "../common/cli.h"

#include <cstdio>
#include <filesystem>
#include <cstdlib>
#include <iostream>
#include <string>

namespace {

// The command line's bounds (issue #38). A texel from 1 mm (CoarseRoomModel.texel_size's least: the
// atlas grows with the inverse square) to 1 m; at most a million cubemaps scored.
constexpr double TEXEL_MIN_M = 0.001, TEXEL_MAX_M = 1.0;
constexpr long MAX_CUBEMAPS = 1000000;

// Why the maps cannot be written into p_out, or "": one that exists, unless p_force; a folder that
// cannot be made or written (issue #38: a read-only --out with --quiet ended with status 0 and
// nothing written). Checked before the evaluation, which takes minutes: the folder is made, and a
// temporary file is made and removed in it.
std::string out_problem(const std::string &p_out, bool p_force) {
	for (const std::string &name : roomprobe::evaluation_output_files()) {
		const std::string problem = roomprobe::cli::output_file_problem("--out", (std::filesystem::path(p_out) / name).string(), p_force);
		if (!problem.empty()) {
			return problem;
		}
	}
	return roomprobe::cli::output_folder_problem("--out", p_out, roomprobe::evaluation_output_files().front());
}

// --compare: B against A, as the evaluation scores a map against the truth.
int compare(const std::string &p_a, const std::string &p_b) {
	roomprobe::Cubemap a, b;
	for (const auto &[path, cubemap] : { std::pair<const std::string &, roomprobe::Cubemap *>{ p_a, &a }, { p_b, &b } }) {
		const std::string error = roomprobe::read_cubemap_exr(path, cubemap);
		if (!error.empty()) {
			std::fprintf(stderr, "roomprobe_eval: --compare: %s\n", error.c_str());
			return 1;
		}
	}
	const roomprobe::CubemapMetrics m = roomprobe::compare_cubemaps(b, a);
	if (!m.ok) {
		std::fprintf(stderr, "roomprobe_eval: --compare: %s and %s are not cubemaps of the same size\n", p_a.c_str(), p_b.c_str());
		return 1;
	}
	std::printf("compare: %s against %s: psnr_db=%.2f psnr_linear_db=%.2f ssim=%.4f irradiance_error=%.5f\n", p_b.c_str(), p_a.c_str(), m.psnr_db,
			m.psnr_linear_db, m.ssim, m.irradiance_error);
	return 0;
}

// After the arguments: the checks of --out, then the evaluation or the budget, printed.
template <typename Usage>
int evaluate(roomprobe::EvaluationOptions options, const Usage &usage, bool budget, bool per_frame, bool quiet, bool force) {
	std::error_code ec;
	if (!options.out.empty() && std::filesystem::exists(options.out, ec) && !std::filesystem::is_directory(options.out, ec)) {
		return usage(("--out " + options.out + " is a file, not a folder: the cubemaps are written into a folder").c_str());
	}
	const std::string kept = options.out.empty() || budget ? "" : out_problem(options.out, force); // --budget writes no maps
	if (!kept.empty()) {
		return usage(kept.c_str());
	}
	if (!quiet) {
		options.progress = [](const std::string &p_line) { std::cerr << p_line << "\n"; };
	}
	if (budget) {
		const roomprobe::BudgetResult table = roomprobe::error_budget(options);
		if (!table.ok) {
			std::fprintf(stderr, "roomprobe_eval: %s\n", table.error.c_str());
			return 1;
		}
		std::cout << roomprobe::format_budget(table);
		return 0;
	}
	const roomprobe::EvaluationResult result = roomprobe::evaluate_recording(options);
	if (!result.ok) {
		std::fprintf(stderr, "roomprobe_eval: %s\n", result.error.c_str());
		return 1;
	}
	std::cout << roomprobe::format_evaluation(result, per_frame);
	if (!result.out_error.empty()) { // the scores stand; the maps asked for are not all there
		std::fprintf(stderr, "roomprobe_eval: --out %s: %s\n", options.out.c_str(), result.out_error.c_str());
		return 1;
	}
	return 0;
}


int run(int argc, char **argv) {
	roomprobe::EvaluationOptions options;
	bool per_frame = false, quiet = false, budget = false, force = false;
	auto usage = [](const char *p_error) {
		std::fprintf(stderr,
				"%s%susage: roomprobe_eval --recording DIR [--out DIR [--force]] [--cubemap-size N] [--per-frame]\n"
				"                      [--texel-size M] [--max-cubemaps K] [--no-dense] [--quiet] [--budget]\n"
				"                      [--rgb-texture] [--no-fisheye] [--dense-range M] [--room FILE] [--backend cpu|vulkan|auto]\n"
				"                      [--lighting-field PRIOR] [--dense-scale N]\n"
				"       roomprobe_eval --compare A.exr B.exr\n"
				"  --out DIR: the last frame's maps of every variant, and the truth's, as NAME.exr and NAME.png;\n"
				"    maps already there are kept and nothing is evaluated, unless --force replaces them\n"
				"  --backend B: where the kernels with a GPU twin run (RigCapture.compute_backend; default cpu)\n"
				"  --compare A.exr B.exr: B's PSNR against A (tone-mapped and linear), two maps --out wrote\n"
				"  --budget: the error budget, the live system with one stage at a time replaced by its oracle\n"
				"  --dense-range M: fuse depth and draw the dense model up to M metres (default 4)\n"
				"  --dense-scale N: the dense pass raycasts at 1 / N of the face size, then upsamples (default 2)\n"
				"  --no-fisheye: the rig as its RGB-D camera alone: the coarse model textured from the RGB camera\n"
				"    (the baseline keeps the fisheye; the same truth, so the runs compare with and without it)\n"
				"  --lighting-field PRIOR: the gain variants' lighting change as a gain field (issue #42), its slope's\n"
				"    prior in log gain per metre (e.g. 0.3); default 0: one gain\n"
				"  --room FILE: the coarse model uses this room.yaml (one found by ./roomprobe room) instead of the\n"
				"    recording's, placed by the two files' initial_rgb_pose; scored against the same truth\n",
				p_error ? "roomprobe_eval: " : "", p_error ? (std::string(p_error) + "\n").c_str() : "");
		return 2;
	};
	roomprobe::cli::Arguments cursor(argc, argv, 1);
	std::string arg;
	while (cursor.next(&arg)) {
		long n = 0;
		double x = 0.0;
		if (arg == "--recording") {
			if (!cursor.value(&options.recording)) {
				return usage("--recording needs a folder");
			}
		} else if (arg == "--out") {
			if (!cursor.value(&options.out)) {
				return usage("--out needs a folder");
			}
		} else if (arg == "--cubemap-size") {
			if (!cursor.integer_in(1, 4096, &n)) {
				return usage("--cubemap-size needs a whole number of pixels in [1, 4096]");
			}
			options.cubemap_size = int(n);
		} else if (arg == "--texel-size") {
			if (!cursor.number_in(TEXEL_MIN_M, TEXEL_MAX_M, &x)) {
				return usage(("--texel-size needs a texel edge in metres in " + roomprobe::cli::range_text(TEXEL_MIN_M, TEXEL_MAX_M)).c_str());
			}
			options.texel_size_m = x;
		} else if (arg == "--max-cubemaps") {
			if (!cursor.integer_in(1, MAX_CUBEMAPS, &n)) {
				return usage(("--max-cubemaps needs a whole number in " + roomprobe::cli::range_text(1, MAX_CUBEMAPS)).c_str());
			}
			options.max_cubemaps = size_t(n);
		} else if (arg == "--dense-range") {
			if (!cursor.positive_number(20.0, &x)) {
				return usage("--dense-range needs a distance in metres in (0, 20]");
			}
			options.dense_range_m = x;
		} else if (arg == "--dense-scale") {
			if (!cursor.integer_in(1, 8, &n)) {
				return usage("--dense-scale needs a whole number in [1, 8]");
			}
			options.dense_scale = int(n);
		} else if (arg == "--lighting-field") {
			if (!cursor.positive_number(10.0, &x)) {
				return usage("--lighting-field needs the slope's prior in log gain per metre, in (0, 10]");
			}
			options.lighting_field_prior_per_m = x;
		} else if (arg == "--room") {
			if (!cursor.value(&options.room_file)) {
				return usage("--room needs a room.yaml (./roomprobe room writes one)");
			}
		} else if (arg == "--force") {
			force = true;
		} else if (arg == "--rgb-texture") {
			options.rgb_texture = true;
		} else if (arg == "--no-fisheye") {
			options.no_fisheye = true;
		} else if (arg == "--backend") {
			std::string name;
			if (!cursor.value(&name) || !roomprobe::compute_backend_from_name(name, &options.compute_backend)) {
				return usage("--backend needs cpu, vulkan or auto");
			}
		} else if (arg == "--compare") {
			std::string a, b;
			if (!cursor.value(&a) || !cursor.value(&b)) {
				return usage("--compare needs two cubemap EXR files");
			}
			return compare(a, b);
		} else if (arg == "--budget") {
			budget = true;
		} else if (arg == "--no-dense") {
			options.dense = false;
		} else if (arg == "--per-frame") {
			per_frame = true;
		} else if (arg == "--quiet") {
			quiet = true;
		} else if (arg == "--help" || arg == "-h") {
			usage(nullptr);
			return 0;
		} else {
			return usage(("unknown argument " + arg).c_str());
		}
	}
	if (options.recording.empty()) {
		return usage("--recording is required");
	}
	return evaluate(options, usage, budget, per_frame, quiet, force);
}

} // namespace

int main(int argc, char **argv) {
	return roomprobe::cli::guarded_main("roomprobe_eval", [&] { return run(argc, argv); });
}
