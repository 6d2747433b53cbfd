// The photometric views' photometric.yaml (calibration/photometric_calibration.h
// load_photometric_views, which ./roomprobe calibrate reads beside the checkerboard views), in a
// folder the target fills once with small fisheye images under the names the synthetic rig writes
// (exposure/000.png ... 016.png, flat_field.png). Any bytes give views or an error that names
// photometric.yaml or the image it names; views that load have a positive reference exposure, one
// positive exposure per sweep image, and images of the fisheye's size (CV_8UC3).
//
// ROOMPROBE_FUZZ_SEED=FILE: writes a small valid photometric.yaml for those images there (a seed)
// and exits.
#include "fuzz_common.h"

#include <calibration/photometric_calibration.h>

#include <opencv2/imgcodecs.hpp>

using namespace roomprobe;

namespace {

namespace fs = std::filesystem;

const cv::Size FISHEYE_SIZE(24, 24);
constexpr int SWEEP_IMAGES = 17; // as the synthetic rig writes them

const char *const SEED =
		"%YAML:1.0\n"
		"---\n"
		"roomprobe_photometric_views: 1\n"
		"reference_exposure_us: 10000.\n"
		"exposure_sweep:\n"
		"   -\n"
		"      image: \"exposure/000.png\"\n"
		"      exposure_us: 625.\n"
		"   -\n"
		"      image: \"exposure/008.png\"\n"
		"      exposure_us: 10000.\n"
		"   - { image: \"exposure/016.png\", exposure_us: 160000 }\n"
		"flat_field:\n"
		"   image: \"flat_field.png\"\n"
		"   exposure_us: 10000.\n";

// The views' folder, with its images written once.
fs::path views_folder() {
	static const fs::path folder = [] {
		const fs::path path = fuzz::scratch() / "photometric";
		fs::create_directories(path / "exposure");
		for (int i = 0; i < SWEEP_IMAGES; i++) {
			char name[32];
			std::snprintf(name, sizeof(name), "%03d.png", i);
			cv::Mat image(FISHEYE_SIZE, CV_8UC3, cv::Scalar(10 + 14 * i, 8 + 12 * i, 6 + 10 * i));
			fuzz::require(cv::imwrite((path / "exposure" / name).string(), image), "a sweep image is written");
		}
		fuzz::require(cv::imwrite((path / "flat_field.png").string(), cv::Mat(FISHEYE_SIZE, CV_8UC3, cv::Scalar(200, 190, 180))),
				"the flat field is written");
		return path;
	}();
	return folder;
}

// The path an error starts with: "PATH: what".
std::string named_path(const std::string &p_error) {
	const size_t colon = p_error.find(": ");
	return colon == std::string::npos ? std::string() : p_error.substr(0, colon);
}

} // namespace

extern "C" int LLVMFuzzerInitialize(int *, char ***) {
	const char *seed = std::getenv("ROOMPROBE_FUZZ_SEED");
	if (seed != nullptr && *seed != '\0') {
		std::ofstream out(seed, std::ios::binary | std::ios::trunc);
		out << SEED;
		out.close(); // std::exit destroys no local: flushed here
		std::exit(out ? 0 : 1);
	}
	return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	const fs::path folder = views_folder();
	const fs::path path = folder / "photometric.yaml";
	fuzz::write_bytes(path, p_data, p_size);
	const PhotometricViews views = load_photometric_views(folder.string(), FISHEYE_SIZE);
	fuzz::require(views.present, "a folder with photometric.yaml has photometric views");
	if (!views.error.empty()) {
		// photometric.yaml, or an image it names (relative to the folder, or an absolute path, which
		// is then in the file's text).
		const std::string named = named_path(views.error);
		const std::string input(reinterpret_cast<const char *>(p_data), p_size);
		fuzz::require(views.error.rfind(path.string() + ": ", 0) == 0 || named.rfind(folder.string() + "/", 0) == 0 ||
						(!named.empty() && input.find(named) != std::string::npos),
				"a photometric error names photometric.yaml or the image it names:", views.error);
		return 0;
	}
	fuzz::require(views.reference_exposure_us > 0.0 && std::isfinite(views.reference_exposure_us), "the reference exposure is positive");
	fuzz::require(views.sweep.size() == views.sweep_exposure_us.size(), "one exposure per sweep image");
	for (size_t i = 0; i < views.sweep.size(); i++) {
		fuzz::require(views.sweep_exposure_us[i] > 0.0 && std::isfinite(views.sweep_exposure_us[i]), "a sweep exposure is positive");
		fuzz::require(views.sweep[i].size() == FISHEYE_SIZE && views.sweep[i].type() == CV_8UC3, "a sweep image is the fisheye's, R, G, B");
	}
	fuzz::require(views.flat_field.empty() || (views.flat_field.size() == FISHEYE_SIZE && views.flat_field.type() == CV_8UC3),
			"the flat field is the fisheye's, R, G, B");
	return 0;
}
