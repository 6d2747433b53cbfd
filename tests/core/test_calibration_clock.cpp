// The clock offset between the cameras (calibration/clock_offset.h), from a synthetic recording
// of the rig moved by hand, whose fisheye clock runs fisheye_time_offset_s (13.7 ms) behind the
// RGB-D camera's: it must come back within 2 ms.

#include "calibration/clock_offset.h"
#include "recording/recording_reader.h"
#include "synth/synth_scene.h"
#include "synth/synth_sequence.h"
#include "synth_test_rig.h"

#include <doctest/doctest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>

using namespace roomprobe;
namespace fs = std::filesystem;

namespace {

// The synthetic rig with a half-size RGB-D camera (quicker to render; its rotations from depth
// stay precise) and the full-size fisheye (whose rotations from rays need its pixels).
Rig half_rig() {
	Rig rig = test_rig();
	rig.rgb.width = 320;
	rig.rgb.height = 240;
	rig.rgb.fx = rig.rgb.fy = 262.5;
	rig.rgb.cx = 159.5;
	rig.rgb.cy = 119.5;
	return rig;
}

struct Recorded {
	fs::path folder;
	explicit Recorded(const std::string &p_name, double p_seconds) {
		folder = fs::temp_directory_path() / ("roomprobe_test_clock_" + p_name + "_" + std::to_string(::getpid()));
		fs::remove_all(folder);
		const synth::SceneResult scene = synth::make_scene("living_room", synth::SceneOptions());
		REQUIRE_MESSAGE(scene.ok, scene.error);
		synth::SequenceOptions options;
		options.duration_s = p_seconds;
		options.cubemap_face_size = 8;
		options.calibration_views = false;
		const synth::SequenceResult written = synth::write_sequence(folder.string(), half_rig(), scene.scene, options);
		REQUIRE_MESSAGE(written.ok, written.error);
	}
	~Recorded() {
		std::error_code ec;
		fs::remove_all(folder, ec);
	}
};

} // namespace

TEST_CASE("clock offset: the fisheye's clock offset comes back within 2 ms from the rig's motion") {
	const Recorded recorded("motion", 5.0);
	RecordingReader reader;
	const RecordingStatus opened = reader.open(recorded.folder.string());
	REQUIRE_MESSAGE(opened.ok, opened.error);
	const Rig truth = half_rig();
	Rig rig = truth;
	rig.fisheye_time_offset_s = 0.0; // what calibration knows before
	const ClockOffsetEstimate estimate = estimate_clock_offset(reader, rig);
	REQUIRE_MESSAGE(estimate.error.empty(), estimate.error);
	MESSAGE("offset " << estimate.offset_s * 1000.0 << " ms (truth " << truth.fisheye_time_offset_s * 1000.0 << "), std " << estimate.std_s * 1000.0
					  << " ms, " << estimate.steps_used << " of " << estimate.fisheye_steps << " fisheye steps, residual " << estimate.residual_rms_deg
					  << " deg, " << estimate.turn_deg << " deg turned");
	CHECK(std::abs(estimate.offset_s - truth.fisheye_time_offset_s) < 0.002);
	CHECK(estimate.std_s < 0.002);
	CHECK(estimate.residual_rms_deg < 0.1); // the rotations agree at the offset: the fisheye's steps are measured well
	// Its figure is independent of where the search starts: a rig file already holding a wrong
	// offset gives the same answer.
	rig.fisheye_time_offset_s = -0.05;
	const ClockOffsetEstimate again = estimate_clock_offset(reader, rig);
	REQUIRE_MESSAGE(again.error.empty(), again.error);
	CHECK(std::abs(again.offset_s - estimate.offset_s) < 0.0005);
}

TEST_CASE("clock offset: a recording too short, or a rig without a fisheye, is refused with the reason") {
	const Recorded recorded("short", 0.25);
	RecordingReader reader;
	REQUIRE(reader.open(recorded.folder.string()).ok);
	const ClockOffsetEstimate short_one = estimate_clock_offset(reader, half_rig());
	CHECK(short_one.error.find("too few frames") != std::string::npos);
	Rig alone = half_rig();
	alone.fisheye = OmniParams();
	CHECK(estimate_clock_offset(reader, alone).error == "the rig has no fisheye");
}
