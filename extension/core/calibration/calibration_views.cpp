#include "calibration_views.h"

#include <recording/recording_types.h>

#include <algorithm>
#include <filesystem>

namespace roomprobe {

namespace fs = std::filesystem;

namespace {

// The images of a folder, sorted: PNG, or JPEG for cameras that give nothing else.
std::vector<fs::path> images_in(const fs::path &p_folder) {
	std::vector<fs::path> files;
	std::error_code ec;
	if (!fs::is_directory(p_folder, ec)) {
		return files;
	}
	for (const fs::directory_entry &entry : fs::directory_iterator(p_folder, ec)) {
		const std::string extension = entry.path().extension().string();
		if (entry.is_regular_file() && (extension == ".png" || extension == ".jpg" || extension == ".jpeg")) {
			files.push_back(entry.path());
		}
	}
	std::sort(files.begin(), files.end());
	return files;
}

// The board of board.yaml (inner_corners_x, inner_corners_y, square_m) or of a synthetic
// recording's boards.yaml (its board map); false when neither is there, error set when one is
// there but unusable.
bool read_board_file(const fs::path &p_folder, BoardSpec *r_board, std::string *r_error) {
	for (const char *name : { "board.yaml", "boards.yaml" }) {
		const fs::path path = p_folder / name;
		if (!fs::exists(path)) {
			continue;
		}
		try {
			cv::FileStorage file(path.string(), cv::FileStorage::READ);
			cv::FileNode node = std::string(name) == "boards.yaml" ? file["board"] : file.root();
			if (node.empty() || node["inner_corners_x"].empty() || node["inner_corners_y"].empty() || node["square_m"].empty()) {
				*r_error = path.string() + ": needs inner_corners_x, inner_corners_y and square_m";
				return true;
			}
			r_board->inner_x = int(node["inner_corners_x"]);
			r_board->inner_y = int(node["inner_corners_y"]);
			r_board->square_m = double(node["square_m"]);
		} catch (const cv::Exception &e) {
			*r_error = path.string() + ": cannot read it (" + e.err + ")";
		}
		return true;
	}
	return false;
}

struct Detected {
	bool ok = false;
	cv::Mat image;
	BoardView view;
};

} // namespace

CalibrationViews load_calibration_views(const std::string &p_folder, const CalibrationViewsOptions &p_options) {
	CalibrationViews result;
	fs::path root(p_folder);
	std::error_code ec;
	if (!fs::is_directory(root, ec)) {
		result.error = p_folder + ": not a folder";
		return result;
	}
	// A recording keeps its views in calibration/ (its rgb/ holds the sequence's frames).
	if (fs::is_directory(root / "calibration", ec) && (fs::exists(root / "rgb.txt", ec) || !fs::is_directory(root / "rgb", ec))) {
		root /= "calibration";
	}
	result.board = p_options.board;
	if (!p_options.board_given) {
		std::string error;
		result.board_from_file = read_board_file(root, &result.board, &error);
		if (!error.empty()) {
			result.error = error;
			return result;
		}
	}
	const std::string board_problem = check_board(result.board);
	if (!board_problem.empty()) {
		result.error = board_problem;
		return result;
	}
	const std::vector<fs::path> rgb_files = images_in(root / "rgb");
	const std::vector<fs::path> fisheye_files = images_in(root / "fisheye");
	std::vector<fs::path> pair_files; // the pairs' RGB images
	for (const fs::path &file : images_in(root / "pairs")) {
		const std::string stem = file.stem().string();
		if (stem.size() > 4 && stem.compare(stem.size() - 4, 4, "_rgb") == 0 && file.extension() == ".png") {
			pair_files.push_back(file);
		}
	}
	if (rgb_files.empty() && fisheye_files.empty() && pair_files.empty()) {
		result.error = root.string() + ": no views (PNG or JPEG images in rgb/ or fisheye/, or pairs/NAME_rgb.png with NAME_fisheye.png; calib/README.md)";
		return result;
	}
	const size_t total = rgb_files.size() + fisheye_files.size() + 2 * pair_files.size();
	cv::Mat fisheye_brightest; // for the image circle
	const auto detect = [&](const fs::path &p_file, bool p_is_rgb) {
		Detected d;
		d.view.name = fs::relative(p_file, root, ec).string();
		if (p_options.progress) {
			p_options.progress(result.images, total, d.view.name);
		}
		result.images++;
		d.image = cv::imread(p_file.string(), cv::IMREAD_GRAYSCALE);
		if (d.image.empty()) {
			result.missed.push_back(d.view.name + ": cannot read the image");
			return d;
		}
		cv::Size &size = p_is_rgb ? result.rgb_size : result.fisheye_size;
		if (size.area() == 0) {
			size = d.image.size();
		} else if (size != d.image.size()) {
			result.missed.push_back(d.view.name + ": " + std::to_string(d.image.cols) + "x" + std::to_string(d.image.rows) + ", the camera's other images are " +
					std::to_string(size.width) + "x" + std::to_string(size.height));
			return d;
		}
		if (!p_is_rgb) {
			keep_brightest(fisheye_brightest, d.image);
		}
		BoardDetection found = detect_board(d.image, result.board);
		if (!found.found) {
			result.missed.push_back(d.view.name + ": the whole board (" + std::to_string(result.board.inner_x) + "x" + std::to_string(result.board.inner_y) +
					" inner corners) was not found");
			return d;
		}
		d.view.corners = std::move(found.corners);
		d.ok = true;
		return d;
	};
	for (const fs::path &file : rgb_files) {
		Detected d = detect(file, true);
		if (d.ok) {
			result.rgb.push_back(std::move(d.view));
		}
	}
	for (const fs::path &file : fisheye_files) {
		Detected d = detect(file, false);
		if (d.ok) {
			result.fisheye.push_back(std::move(d.view));
		}
	}
	for (const fs::path &file : pair_files) {
		const std::string stem = file.stem().string();
		const std::string name = stem.substr(0, stem.size() - 4);
		const fs::path fisheye_file = file.parent_path() / (name + "_fisheye.png");
		if (!fs::exists(fisheye_file, ec)) {
			result.missed.push_back(fs::relative(file, root, ec).string() + ": no " + name + "_fisheye.png beside it");
			continue;
		}
		Detected rgb = detect(file, true);
		Detected fisheye = detect(fisheye_file, false);
		if (rgb.ok) {
			result.rgb.push_back(rgb.view);
		}
		if (fisheye.ok) {
			result.fisheye.push_back(fisheye.view);
		}
		if (!rgb.ok || !fisheye.ok) {
			continue;
		}
		BoardPair pair;
		pair.rgb = std::move(rgb.view);
		pair.fisheye = std::move(fisheye.view);
		const fs::path depth_file = file.parent_path() / (name + "_depth.png");
		if (fs::exists(depth_file, ec)) {
			const cv::Mat raw = cv::imread(depth_file.string(), cv::IMREAD_UNCHANGED);
			if (raw.type() != CV_16UC1 || raw.size() != rgb.image.size()) {
				result.missed.push_back(fs::relative(depth_file, root, ec).string() + ": not a 16-bit depth image of the RGB image's size; depth not checked on it");
			} else {
				pair.depth_m = depth_metres_from_raw(raw, p_options.depth_scale_m);
			}
		}
		result.pairs.push_back(std::move(pair));
	}
	if (p_options.progress) {
		p_options.progress(total, total, "");
	}
	result.fisheye_circle = find_image_circle(fisheye_brightest);
	return result;
}

} // namespace roomprobe
