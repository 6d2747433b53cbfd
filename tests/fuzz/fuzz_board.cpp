// The calibration board file that ./roomprobe calibrate reads from the views' folder
// (calibration/calibration_views.h load_calibration_views): the same bytes as a hand-written
// board.yaml (inner_corners_x, inner_corners_y, square_m) and as a synthetic recording's
// boards.yaml (its board map), each in a folder with no views. Any bytes give an error that
// names the board file, or a board from the file that passes check_board, after which the
// folder is refused for having no views (naming the folder, not the board file).
#include "fuzz_common.h"

#include <calibration/calibration_views.h>

using namespace roomprobe;

namespace {

namespace fs = std::filesystem;

void check_board_file(const uint8_t *p_data, size_t p_size, const char *p_name) {
	const fs::path folder = fuzz::scratch() / (std::string("views_") + p_name);
	fs::create_directories(folder);
	const fs::path path = folder / p_name;
	fuzz::write_bytes(path, p_data, p_size);
	const CalibrationViews views = load_calibration_views(folder.string(), CalibrationViewsOptions());
	fuzz::require(!views.error.empty(), "a folder without views is refused");
	if (views.error.rfind(path.string() + ": ", 0) == 0) {
		return; // the board file refused, named
	}
	fuzz::require(views.board_from_file, "a board file that is not refused gives the board:", views.error);
	fuzz::require(check_board(views.board).empty(), "a board from the file passes check_board:", check_board(views.board));
	fuzz::require(views.error.rfind(folder.string() + ": no views", 0) == 0, "a good board file leaves only the missing views:", views.error);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *p_data, size_t p_size) {
	check_board_file(p_data, p_size, "board.yaml");
	check_board_file(p_data, p_size, "boards.yaml");
	return 0;
}
