#include "calibration_views.h"
#include <io/yaml_fields.h>

#include <io/image_codec.h>
#include <io/input_path.h>

#include <recording/recording_reader.h>
#include <recording/recording_types.h>

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <utility>

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
bool read_board_file(const fs::path &p_folder, BoardSpec *r_board, std::string *r_file, std::string *r_error) {
	for (const char *name : { "board.yaml", "boards.yaml" }) {
		const fs::path path = p_folder / name;
		if (!fs::exists(path)) {
			continue;
		}
		*r_file = path.string();
		try {
			cv::FileStorage file;
			const std::string problem = open_yaml_file(path.string(), &file);
			if (!problem.empty()) {
				*r_error = problem;
				return true;
			}
			cv::FileNode node = std::string(name) == "boards.yaml" ? file["board"] : file.root();
			if (node.empty() || node["inner_corners_x"].empty() || node["inner_corners_y"].empty() || node["square_m"].empty()) {
				*r_error = path.string() + ": needs inner_corners_x, inner_corners_y and square_m";
				return true;
			}
			// Taken as written, or refused naming the field and what it holds: a count of 9.7 was
			// rounded to 10 and "nine" read as 0, and the board echoed with numbers never typed (#38).
			const std::string prefix = std::string(name) == "boards.yaml" ? "board." : "";
			YamlFieldReader reader(YamlFieldReader::NonFinite::Refuse);
			for (const auto &[key, corners] : { std::pair<const char *, int *>{ "inner_corners_x", &r_board->inner_x }, { "inner_corners_y", &r_board->inner_y } }) {
				const cv::FileNode count = node[key];
				if (count.isReal()) {
					char text[64];
					const std::to_chars_result written = std::to_chars(text, text + sizeof(text), double(count));
					reader.fail(prefix + key, "must be a whole number of inner corners (got " + std::string(text, written.ptr) + ")");
				} else {
					reader.integer(node, prefix, key, corners);
				}
				if (!reader.error.empty()) {
					*r_error = path.string() + ": " + reader.error;
					return true;
				}
			}
			if (!reader.real(node, prefix, "square_m", &r_board->square_m)) {
				*r_error = path.string() + ": " + reader.error;
				return true;
			}
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

// Evenly spread indices: at most p_keep of p_count (all when fewer).
std::vector<size_t> spread(size_t p_count, size_t p_keep) {
	std::vector<size_t> indices;
	if (p_count == 0 || p_keep == 0) {
		return indices;
	}
	const size_t keep = std::min(p_count, p_keep);
	for (size_t i = 0; i < keep; i++) {
		indices.push_back(keep == 1 ? 0 : i * (p_count - 1) / (keep - 1));
	}
	return indices;
}

// The views in a recording's own frames (a recording of the board held before the rig): every
// few frames of each camera where the whole board is found, and pairs of an RGB-D frame and the
// fisheye frame taken within PAIR_TOLERANCE_S of it (on the RGB-D clock, through the recording's
// fisheye_time_offset_s; 0 for live recordings, one clock).
constexpr double PAIR_TOLERANCE_S = 0.02;
constexpr size_t CANDIDATES = 120; // frames examined per camera
constexpr size_t KEEP_VIEWS = 30; // kept per camera
constexpr size_t KEEP_PAIRS = 15;

void load_recording_views(const fs::path &p_root, const CalibrationViewsOptions &p_options, CalibrationViews *r_views) {
	RecordingReader reader;
	const RecordingStatus opened = reader.open(p_root.string());
	if (!opened.ok) {
		r_views->error = opened.error;
		return;
	}
	const Rig &rig = reader.get_rig();
	const std::vector<size_t> rgb_candidates = spread(reader.rgbd_count(), CANDIDATES);
	const std::vector<size_t> fisheye_candidates = rig.has_fisheye() ? spread(reader.fisheye_count(), CANDIDATES) : std::vector<size_t>();
	const size_t total = rgb_candidates.size() + fisheye_candidates.size();
	struct Found {
		size_t index;
		double time_s; // RGB-D clock
		BoardView view;
	};
	std::vector<Found> rgb_found, fisheye_found;
	cv::Mat fisheye_brightest;
	size_t done = 0, unreadable = 0;
	const auto progress = [&](const std::string &p_name) {
		if (p_options.progress) {
			p_options.progress(done, total, p_name);
		}
		done++;
		r_views->images++;
	};
	for (size_t k : fisheye_candidates) {
		const std::string name = "fisheye frame " + std::to_string(k);
		progress(name);
		const FisheyeFrameResult read = reader.read_fisheye(k);
		if (!read.ok) {
			unreadable++;
			continue;
		}
		const cv::Mat gray = gray_8bit(read.frame.image);
		r_views->fisheye_size = gray.size();
		keep_brightest(fisheye_brightest, gray);
		BoardDetection found = detect_board(gray, r_views->board);
		if (found.found) {
			fisheye_found.push_back({ k, read.frame.timestamp_s + rig.fisheye_time_offset_s, { name, std::move(found.corners) } });
		}
	}
	for (size_t i : rgb_candidates) {
		const std::string name = "RGB frame " + std::to_string(i);
		progress(name);
		const RgbdFrameResult read = reader.read_rgbd(i);
		if (!read.ok) {
			unreadable++;
			continue;
		}
		r_views->rgb_size = read.frame.rgb.size();
		BoardDetection found = detect_board(gray_8bit(read.frame.rgb), r_views->board);
		if (!found.found) {
			continue;
		}
		Found rgb{ i, read.frame.timestamp_s, { name, std::move(found.corners) } };
		// Its pair: the fisheye frame with the board nearest in time, if near enough.
		const Found *nearest = nullptr;
		for (const Found &f : fisheye_found) {
			if (std::abs(f.time_s - rgb.time_s) <= PAIR_TOLERANCE_S && (!nearest || std::abs(f.time_s - rgb.time_s) < std::abs(nearest->time_s - rgb.time_s))) {
				nearest = &f;
			}
		}
		if (nearest && r_views->pairs.size() < 4 * KEEP_PAIRS) {
			BoardPair pair;
			pair.rgb = rgb.view;
			pair.fisheye = nearest->view;
			pair.rgb_image = read.frame.rgb;
			pair.depth_m = read.frame.depth_m;
			const FisheyeFrameResult fisheye = reader.read_fisheye(nearest->index);
			if (fisheye.ok && fisheye.frame.image.type() == CV_8UC3) {
				pair.fisheye_image = fisheye.frame.image;
			}
			r_views->pairs.push_back(std::move(pair));
		}
		rgb_found.push_back(std::move(rgb));
	}
	if (p_options.progress) {
		p_options.progress(total, total, "");
	}
	for (size_t i : spread(rgb_found.size(), KEEP_VIEWS)) {
		r_views->rgb.push_back(rgb_found[i].view);
	}
	for (size_t i : spread(fisheye_found.size(), KEEP_VIEWS)) {
		r_views->fisheye.push_back(fisheye_found[i].view);
	}
	std::vector<BoardPair> pairs;
	for (size_t i : spread(r_views->pairs.size(), KEEP_PAIRS)) {
		pairs.push_back(std::move(r_views->pairs[i]));
	}
	r_views->pairs = std::move(pairs);
	r_views->missed.push_back(std::to_string(rgb_candidates.size() - rgb_found.size()) + " of " + std::to_string(rgb_candidates.size()) +
			" RGB frames and " + std::to_string(fisheye_candidates.size() - fisheye_found.size()) + " of " + std::to_string(fisheye_candidates.size()) +
			" fisheye frames examined did not show the whole board" + (unreadable ? " (" + std::to_string(unreadable) + " unreadable)" : std::string()));
	r_views->fisheye_circle = find_image_circle(fisheye_brightest);
}

// The views of a folder of images: rgb/, fisheye/ and pairs/ (calib/README.md).
struct FolderViews {
	const fs::path &root;
	const CalibrationViewsOptions &options;
	CalibrationViews &result;
	size_t total = 0; // images to read, for the progress
	cv::Mat fisheye_brightest; // for the image circle

	// One image read, checked against its camera's size and searched for the whole board; a miss
	// is said in result.missed.
	Detected detect(const fs::path &p_file, bool p_is_rgb);
	// A pair (pairs/NAME_rgb.png, NAME_fisheye.png and optionally NAME_depth.png): each view where
	// the board is found, and the pair when both are.
	void add_pair(const fs::path &p_file);
};

Detected FolderViews::detect(const fs::path &p_file, bool p_is_rgb) {
	std::error_code ec;
	Detected d;
	d.view.name = fs::relative(p_file, root, ec).string();
	if (options.progress) {
		options.progress(result.images, total, d.view.name);
	}
	result.images++;
	const std::string error = image_read(p_file.string(), ImageReadMode::Gray8, &d.image);
	if (!error.empty()) {
		d.image = cv::Mat();
		result.missed.push_back(d.view.name + ": cannot read the image (" + error + ")");
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
		result.missed.push_back(d.view.name + ": the whole board (" + board_text(result.board) + ") was not found");
		return d;
	}
	d.view.corners = std::move(found.corners);
	d.ok = true;
	return d;
}

void FolderViews::add_pair(const fs::path &p_file) {
	std::error_code ec;
	const std::string stem = p_file.stem().string();
	const std::string name = stem.substr(0, stem.size() - 4);
	const fs::path fisheye_file = p_file.parent_path() / (name + "_fisheye.png");
	if (!fs::exists(fisheye_file, ec)) {
		result.missed.push_back(fs::relative(p_file, root, ec).string() + ": no " + name + "_fisheye.png beside it");
		return;
	}
	Detected rgb = detect(p_file, true);
	Detected fisheye = detect(fisheye_file, false);
	if (rgb.ok) {
		result.rgb.push_back(rgb.view);
	}
	if (fisheye.ok) {
		result.fisheye.push_back(fisheye.view);
	}
	if (!rgb.ok || !fisheye.ok) {
		return;
	}
	BoardPair pair;
	pair.rgb = std::move(rgb.view);
	pair.fisheye = std::move(fisheye.view);
	for (const auto &[path, image] : { std::pair(p_file, &pair.rgb_image), std::pair(fisheye_file, &pair.fisheye_image) }) {
		cv::Mat bgr;
		if (image_read(path.string(), ImageReadMode::Bgr8, &bgr).empty()) {
			cv::cvtColor(bgr, *image, cv::COLOR_BGR2RGB);
		}
	}
	const fs::path depth_file = p_file.parent_path() / (name + "_depth.png");
	if (fs::exists(depth_file, ec)) {
		cv::Mat raw;
		image_read(depth_file.string(), ImageReadMode::Unchanged, &raw);
		if (raw.type() != CV_16UC1 || raw.size() != rgb.image.size()) {
			result.missed.push_back(fs::relative(depth_file, root, ec).string() + ": not a 16-bit depth image of the RGB image's size; depth not checked on it");
		} else {
			pair.depth_m = depth_metres_from_raw(raw, options.depth_scale_m);
		}
	}
	result.pairs.push_back(std::move(pair));
}

// The pairs' RGB images: pairs/NAME_rgb.png.
std::vector<fs::path> pair_rgb_files(const fs::path &p_root) {
	std::vector<fs::path> pair_files;
	for (const fs::path &file : images_in(p_root / "pairs")) {
		const std::string stem = file.stem().string();
		if (stem.size() > 4 && stem.compare(stem.size() - 4, 4, "_rgb") == 0 && file.extension() == ".png") {
			pair_files.push_back(file);
		}
	}
	return pair_files;
}

void load_folder_views(const fs::path &p_root, const CalibrationViewsOptions &p_options, CalibrationViews *r_views) {
	const std::vector<fs::path> rgb_files = images_in(p_root / "rgb");
	const std::vector<fs::path> fisheye_files = images_in(p_root / "fisheye");
	const std::vector<fs::path> pair_files = pair_rgb_files(p_root);
	if (rgb_files.empty() && fisheye_files.empty() && pair_files.empty()) {
		r_views->error = p_root.string() + ": no views (PNG or JPEG images in rgb/ or fisheye/, or pairs/NAME_rgb.png with NAME_fisheye.png; calib/README.md)";
		return;
	}
	const size_t total = rgb_files.size() + fisheye_files.size() + 2 * pair_files.size();
	FolderViews folder{ p_root, p_options, *r_views, total, cv::Mat() };
	for (const fs::path &file : rgb_files) {
		Detected d = folder.detect(file, true);
		if (d.ok) {
			r_views->rgb.push_back(std::move(d.view));
		}
	}
	for (const fs::path &file : fisheye_files) {
		Detected d = folder.detect(file, false);
		if (d.ok) {
			r_views->fisheye.push_back(std::move(d.view));
		}
	}
	for (const fs::path &file : pair_files) {
		folder.add_pair(file);
	}
	if (p_options.progress) {
		p_options.progress(total, total, "");
	}
	r_views->fisheye_circle = find_image_circle(folder.fisheye_brightest);
}

} // namespace

CalibrationViews load_calibration_views(const std::string &p_folder, const CalibrationViewsOptions &p_options) {
	CalibrationViews result;
	fs::path root(p_folder);
	std::error_code ec;
	result.error = input_folder_problem(p_folder);
	if (!result.error.empty()) {
		return result;
	}
	// A recording keeps its views in calibration/ (its rgb/ holds the sequence's frames); one
	// without that folder is a recording of the board itself, whose frames are the views.
	const bool recording = fs::exists(root / "rgb.txt", ec);
	if (fs::is_directory(root / "calibration", ec) && (recording || !fs::is_directory(root / "rgb", ec))) {
		root /= "calibration";
	}
	const bool from_frames = recording && root == fs::path(p_folder);
	result.folder = root.string();
	result.board = p_options.board;
	std::string board_file;
	if (!p_options.board_given) {
		std::string error;
		result.board_from_file = read_board_file(root, &result.board, &board_file, &error);
		if (!error.empty()) {
			result.error = error;
			return result;
		}
	}
	const std::string board_problem = check_board(result.board);
	if (!board_problem.empty()) {
		result.error = result.board_from_file ? board_file + ": " + board_problem : board_problem;
		return result;
	}
	if (from_frames) {
		if (!p_options.board_given && !result.board_from_file) {
			result.error = root.string() + ": which board? Put a board.yaml in the recording (inner_corners_x, inner_corners_y, square_m) or pass --board and --square-m";
			return result;
		}
		load_recording_views(root, p_options, &result);
		return result;
	}
	load_folder_views(root, p_options, &result);
	return result;
}

} // namespace roomprobe
