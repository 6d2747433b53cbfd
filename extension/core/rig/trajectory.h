#pragma once
// A camera's timed poses (the RGB-D camera's, from tracking or ground truth), the pose at any
// instant between two of them (paper §4.3), and the TUM RGB-D trajectory format.

#include <io/replace_file.h>
#include <math/pose.h>

#include <fstream>
#include <string>
#include <vector>

namespace roomprobe {

struct TimedPose {
	double t_s = 0.0; // seconds, on the clock of the camera whose poses these are
	Pose world_from_camera;
};

// Samples with strictly increasing timestamps, finite values and unit rotations: a Trajectory
// never holds anything else, so pose_at need not check again.
class Trajectory {
public:
	// Quaternions may be off unit norm by this much (rounded by a file or a tracker); they are
	// normalised. Anything further off is an error.
	static constexpr double UNIT_TOLERANCE = 1e-6;

	// Replaces every sample; on an error (naming the index) the trajectory is left unchanged.
	bool set_samples(std::vector<TimedPose> p_samples, std::string *r_error);
	// Appends one sample, which must come after the last one (live tracking).
	bool append(const TimedPose &p_sample, std::string *r_error);
	void clear() { samples.clear(); }

	const std::vector<TimedPose> &get_samples() const { return samples; }
	size_t size() const { return samples.size(); }
	bool is_empty() const { return samples.empty(); }
	// The first and last timestamps; 0 for an empty trajectory.
	double get_start_s() const { return samples.empty() ? 0.0 : samples.front().t_s; }
	double get_end_s() const { return samples.empty() ? 0.0 : samples.back().t_s; }

	// The pose at p_t_s: lerp/slerp between the two samples around it (a sample's own timestamp
	// gives that sample exactly). Outside [start, end] it is an error, unless within
	// p_extrapolation_tolerance_s of an end: then the first or last pair is extended at constant
	// velocity (a one-sample trajectory holds its pose). On an error r_pose is left unchanged.
	bool pose_at(double p_t_s, Pose *r_pose, std::string *r_error, double p_extrapolation_tolerance_s = 0.0) const;

private:
	std::vector<TimedPose> samples;
};

struct TrajectoryLoadResult {
	bool ok = false;
	std::string error; // names the file and the line, e.g. "poses.txt:12: qw: not a number ('0.7x')"
	Trajectory trajectory;
};

// Reads a TUM RGB-D trajectory: one pose a line, 'timestamp tx ty tz qx qy qz qw' (seconds,
// metres, world_from_camera); blank lines and lines starting with '#' are skipped. Quaternions
// within TUM_UNIT_TOLERANCE of unit norm are normalised (TUM files often keep 4 decimals).
// An empty trajectory is an error.
inline constexpr double TUM_UNIT_TOLERANCE = 1e-3;
TrajectoryLoadResult load_tum_trajectory(const std::string &p_path);
// Writes it in the same format, every number with enough digits to read back the same double,
// after p_header's lines as '#' comments. Returns an empty string, or the error naming the file.
std::string save_tum_trajectory(const std::string &p_path, const Trajectory &p_trajectory, const std::vector<std::string> &p_header = {});

// Writes a TUM trajectory file pose by pose, as a tracker gives them, with '#' comment lines
// anywhere (load_tum_trajectory and TUM's own tools skip them). Each call returns an empty
// string or the error naming the file; after an error the writer writes nothing more. The lines
// go to a temporary file beside the path, renamed over it by a close() without errors: the path
// is replaced whole or left as it was (io/replace_file.h).
class TumTrajectoryWriter {
public:
	TumTrajectoryWriter() = default;
	TumTrajectoryWriter(const TumTrajectoryWriter &) = delete;
	TumTrajectoryWriter &operator=(const TumTrajectoryWriter &) = delete;
	~TumTrajectoryWriter() { close(); }

	// Begins the file at p_path (a folder or a device there is refused) with p_header's lines as
	// comments, then the column line '# timestamp tx ty tz qx qy qz qw'.
	std::string open(const std::string &p_path, const std::vector<std::string> &p_header = {});
	bool is_open() const { return file.is_open(); }
	// One pose line; timestamps must increase strictly, poses be finite with a unit rotation.
	std::string add_pose(const TimedPose &p_sample);
	// '# ' + p_text (each line of it, when it has several).
	std::string add_comment(const std::string &p_text);
	std::string close();

private:
	std::string write(const std::string &p_text);

	FileReplacement replacement;
	std::ofstream file; // on the replacement's temporary file
	std::string path;
	std::string error;
	bool has_last = false;
	double last_t_s = 0.0;
};

} // namespace roomprobe
