// eval/evaluate.h on a short synthetic recording: the coarse model beats §5.3's baseline.

#include <io/opencv.h>

#include "eval/evaluate.h"
#include "synth/synth_sequence.h"
#include "synth_test_rig.h"

#include <doctest/doctest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

using namespace roomprobe;
namespace fs = std::filesystem;

namespace {

struct EvalTempFolder {
	fs::path path;
	EvalTempFolder() {
		path = fs::temp_directory_path() / ("roomprobe_test_eval_" + std::to_string(::getpid()));
		fs::remove_all(path);
	}
	~EvalTempFolder() {
		std::error_code ec;
		fs::remove_all(path, ec);
	}
};

// The synthetic rig with a half-resolution (512 x 512) fisheye, to render faster.
Rig half_fisheye_rig() {
	Rig rig = test_rig();
	rig.fisheye = scaled_test_fisheye(2);
	return rig;
}

// A short synthetic living-room recording with 32-px ground-truth cubemaps, in p_folder, by p_rig.
synth::SequenceResult write_living_room(const EvalTempFolder &p_folder, double p_seconds, const Rig &p_rig = half_fisheye_rig()) {
	synth::SceneOptions scene_options;
	scene_options.duration_s = p_seconds;
	const synth::SceneResult scene = synth::make_scene("living_room", scene_options);
	REQUIRE_MESSAGE(scene.ok, scene.error);
	synth::SequenceOptions sequence;
	sequence.duration_s = p_seconds;
	sequence.seed = 3;
	sequence.cubemap_face_size = 32;
	sequence.calibration_views = false;
	const synth::SequenceResult written = synth::write_sequence(p_folder.path.string(), p_rig, scene.scene, sequence);
	REQUIRE_MESSAGE(written.ok, written.error);
	return written;
}

// The evaluation's options for the recording in p_folder, with texels of p_texel_size_m.
EvaluationOptions options_for(const EvalTempFolder &p_folder, double p_texel_size_m) {
	EvaluationOptions options;
	options.recording = p_folder.path.string();
	options.texel_size_m = p_texel_size_m;
	return options;
}

} // namespace

TEST_CASE("eval: on living_room the full coarse pipeline beats the 5.3 baseline, and the dense model improves on it") {
	EvalTempFolder folder;
	const synth::SequenceResult written = write_living_room(folder, 1.5); // the ceiling light switches on at 0.75 s

	EvaluationOptions options;
	options.recording = folder.path.string();
	options.out = (folder.path / "eval").string();
	options.texel_size_m = 0.04;
	const EvaluationResult result = evaluate_recording(options);
	REQUIRE_MESSAGE(result.ok, result.error);
	const std::string table = format_evaluation(result, false);
	MESSAGE(table);
	CHECK(result.linearised);
	CHECK(result.cubemaps == written.timings.cubemaps);
	CHECK(result.light_switch_s == doctest::Approx(0.75));
	REQUIRE(result.variants.size() == size_t(VARIANT_COUNT));
	const VariantScores &baseline = result.variants[VARIANT_BASELINE];
	const VariantScores &full = result.variants[VARIANT_LIGHT_GAIN];
	const VariantScores &paper = result.variants[VARIANT_LIGHT_ADDITIVE];
	CHECK(full.mean_psnr_db > baseline.mean_psnr_db); // the paper's §5.3 claim
	CHECK(paper.mean_psnr_db > baseline.mean_psnr_db);
	CHECK(result.variants[VARIANT_INPAINT].mean_psnr_db > result.variants[VARIANT_COARSE].mean_psnr_db);
	// §4.7: the table and the objects on it, which the coarse model cannot have, come from the
	// dense model, with true poses and with the live system's own tracking.
	CHECK(result.variants[VARIANT_DENSE_TRUE_POSES].mean_psnr_db > full.mean_psnr_db);
	CHECK(result.variants[VARIANT_DENSE_SLAM].mean_psnr_db > full.mean_psnr_db);
	CHECK(result.slam.lost == 0);
	CHECK(result.slam.ate_rmse_m < 0.01); // the target on synthetic sequences
	for (const char *file : { "baseline.exr", "coarse_light_gain.png", "ground_truth.exr", "dense_slam.png" }) {
		CHECK(fs::exists(folder.path / "eval" / file));
	}
}

TEST_CASE("eval: a recording with no fisheye or no RGB-D frames is refused, not scored") {
	EvalTempFolder folder;
	write_living_room(folder, 0.5);
	const EvaluationOptions options = options_for(folder, 0.08);
	// Empty indexes (the header lines stay): once a full score table from nothing, status 0.
	for (const char *index : { "fisheye.txt", "rgb.txt" }) {
		CAPTURE(index);
		const fs::path path = folder.path / index, kept = folder.path / (std::string(index) + ".kept");
		fs::copy_file(path, kept, fs::copy_options::overwrite_existing);
		{
			std::ofstream empty(path, std::ios::trunc);
			empty << "# emptied by the test\n";
		}
		const EvaluationResult result = evaluate_recording(options);
		CHECK_FALSE(result.ok);
		CHECK(result.error.find(std::string(index) == "fisheye.txt" ? "no fisheye frames" : "no RGB-D frames") != std::string::npos);
		fs::copy_file(kept, path, fs::copy_options::overwrite_existing);
	}
}

// Issue #43: a recording of the RGB-D camera alone is scored from its RGB views; the same sweep
// with the fisheye, scored with no_fisheye, is the same evaluation: the same RGB-D frames, and the
// truth at the same times (the fisheye's clock offset is 0 here: without a fisheye the truth keeps
// the fisheye clock's times, which a clock offset would shift).
TEST_CASE("eval: a recording of an RGB-D camera alone is scored from its RGB views, as --no-fisheye scores one with a fisheye") {
	EvalTempFolder alone, with_fisheye;
	with_fisheye.path += "_fisheye";
	fs::remove_all(with_fisheye.path);
	Rig one_clock = half_fisheye_rig();
	one_clock.fisheye_time_offset_s = 0.0;
	const synth::SequenceResult written = write_living_room(alone, 0.5, rgbd_camera_alone(one_clock));
	CHECK(written.timings.fisheye_frames == 0);
	CHECK(written.timings.cubemaps > 0);
	write_living_room(with_fisheye, 0.5, one_clock);
	EvaluationOptions options = options_for(alone, 0.08);
	options.dense = false;
	const EvaluationResult scored = evaluate_recording(options);
	REQUIRE_MESSAGE(scored.ok, scored.error);
	MESSAGE(format_evaluation(scored, false));
	CHECK(scored.cubemaps == written.timings.cubemaps);
	CHECK(scored.fisheye_frames_used == 0);
	// The baseline (5.3) has no frame: a black map. The RGB views' map holds the room's light.
	CHECK(scored.variants[VARIANT_INPAINT].mean_psnr_db > scored.variants[VARIANT_BASELINE].mean_psnr_db + 3.0);
	options = options_for(with_fisheye, 0.08);
	options.dense = false;
	options.no_fisheye = true;
	const EvaluationResult stripped = evaluate_recording(options);
	REQUIRE_MESSAGE(stripped.ok, stripped.error);
	REQUIRE(stripped.cubemaps == scored.cubemaps);
	for (int v : { VARIANT_COARSE, VARIANT_INPAINT, VARIANT_LIGHT_GAIN }) {
		CAPTURE(v);
		CHECK(stripped.variants[size_t(v)].mean_psnr_db == doctest::Approx(scored.variants[size_t(v)].mean_psnr_db).epsilon(1e-9));
	}
}

// Issue #38: "see the messages above" with no messages above (the tool's --quiet, the nodes), and a
// --out that could not be written while the evaluation still succeeded (status 0, nothing written).
TEST_CASE("eval: why no frame could be used is in the error itself, and maps that could not be written are reported") {
	EvalTempFolder folder;
	write_living_room(folder, 0.5);
	EvaluationOptions options = options_for(folder, 0.08);
	options.dense = false;

	// --out a file: the maps cannot be written; the scores stand, and out_error says why.
	const fs::path file = folder.path / "a_file";
	std::ofstream(file) << "not a folder";
	options.out = file.string();
	EvaluationResult result = evaluate_recording(options);
	REQUIRE_MESSAGE(result.ok, result.error);
	CHECK(result.out_error.find(file.string() + ": cannot create the folder") != std::string::npos);
	// A folder where one map goes: that map is named, the others are written.
	options.out = (folder.path / "maps").string();
	fs::create_directories(folder.path / "maps" / "coarse.exr");
	result = evaluate_recording(options);
	REQUIRE_MESSAGE(result.ok, result.error);
	CHECK(result.out_error.find("coarse.exr: is a folder, not a file") != std::string::npos);
	CHECK(fs::exists(folder.path / "maps" / "baseline.exr"));
	options.out = (folder.path / "fine").string();
	result = evaluate_recording(options);
	CHECK(result.out_error.empty());

	// Every fisheye frame's data overwritten (its length and header kept, so that it passes the
	// reader's checks at open and fails when read): the error says how many were skipped and why
	// the first was.
	options.out.clear();
	for (const fs::directory_entry &entry : fs::directory_iterator(folder.path / "fisheye")) {
		std::fstream frame(entry.path(), std::ios::in | std::ios::out | std::ios::binary);
		const std::streamoff size = std::streamoff(fs::file_size(entry.path()));
		frame.seekp(size / 2);
		frame << std::string(size_t(size - size / 2), '\x5a');
	}
	result = evaluate_recording(options);
	CAPTURE(result.error);
	CHECK_FALSE(result.ok);
	CHECK(result.error.find("fisheye frames could be used: ") != std::string::npos);
	CHECK(result.error.find(" skipped; the first: ") != std::string::npos);
	CHECK(result.error.find("see the messages above") == std::string::npos);
}

TEST_CASE("eval: the error budget has the live system and each oracle's row, scored at the sweep's moments") {
	EvalTempFolder folder;
	write_living_room(folder, 1.0);
	EvaluationOptions options = options_for(folder, 0.04);
	options.max_cubemaps = 6;
	const BudgetResult budget = error_budget(options);
	REQUIRE_MESSAGE(budget.ok, budget.error);
	const std::string table = format_budget(budget);
	MESSAGE(table);
	REQUIRE(budget.rows.size() == 11);
	CHECK(budget.missing.empty());
	CHECK(budget.rows[0].what.find("the live system") == 0);
	CHECK(budget.rows[1].what == "oracle: true poses");
	// The models' oracles put the truth into the live map where their model would show it: never
	// worse, and better wherever the live map was wrong there (the coarse texture's ceiling light,
	// the table's objects the dense model has not seen in a second).
	CHECK(budget.rows[4].what.find("oracle: true coarse texture") == 0);
	CHECK(budget.rows[5].what.find("oracle: true dense") == 0);
	for (const size_t oracle : { size_t(4), size_t(5) }) {
		CHECK(budget.rows[oracle].scores.mean_psnr_db > budget.rows[0].scores.mean_psnr_db + 0.1);
	}
	for (const BudgetRow &row : budget.rows) {
		CAPTURE(row.what);
		REQUIRE(row.scores.frames.size() == 6);
		CHECK(std::isfinite(row.scores.mean_psnr_mu_db));
		CHECK(row.scores.mean_psnr_worst5_db < row.scores.mean_psnr_db); // the worst directions are worse than the mean
		CHECK(row.scores.at_moment[2] == -1); // a 1-s recording has no 10-s moment
	}
	// The dense model's term: leaving it out costs PSNR (the table is only in the dense model).
	CHECK(budget.rows[1].scores.mean_psnr_db > budget.rows[2].scores.mean_psnr_db);
	CHECK(table.find("shorter than 10 s") != std::string::npos);
	// The direction split covers the whole map; the fisheye saw most of the room in a second of the
	// sweep, the table (RGB-D only) is in view, and what nobody saw is worse than what the fisheye saw.
	REQUIRE(budget.shipped.directions_at_s >= 0.0);
	double shares = 0.0;
	for (const DirectionClassScores &c : budget.shipped.directions) {
		shares += c.share;
	}
	CHECK(shares == doctest::Approx(1.0).epsilon(1e-9));
	CHECK(budget.shipped.directions[DIRECTIONS_FISHEYE].share > 0.3);
	CHECK(budget.shipped.directions[DIRECTIONS_RGBD_ONLY].share > 0.0);
	// The mirror spheres at the probe, against the ray-traced reference: reading the true map where
	// the reflected ray meets the scene beats reading it along the ray (the table's objects are
	// centimetres from the probe).
	REQUIRE(!budget.shipped.mirrors.empty());
	for (const EvaluationResult::MirrorRow &row : budget.shipped.mirrors) {
		CAPTURE(row.radius_m);
		CHECK(row.scores.views > 0);
		if (row.true_map) {
			CHECK(row.scores.psnr_parallax_db > row.scores.psnr_plain_db + 1.0);
		}
	}
}
