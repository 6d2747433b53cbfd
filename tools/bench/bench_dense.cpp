// Dense SLAM alone (DenseSlam: the engine needs a rig with a fisheye, which datasets have not):
// slam --tum DIR, slam --7scenes DIR, and slam --recording on a SLAM-only recording.

#include "bench_setup.h"

#include <camera/pinhole_camera.h>
#include <recording/frames_dataset.h>
#include <recording/tum_dataset.h>

namespace roomprobe::bench {

namespace {

// Where SLAM starts: room.yaml's initial pose at frame 0; else the first frame the ground truth
// covers, at its pose, so that both share the world frame; else the identity (timings only).
// Returns the start's description.
std::string find_start(const DenseSource &p_source, const Trajectory &p_truth, size_t *r_first, Pose *r_initial) {
	const RecordingReader &reader = *p_source.reader;
	*r_first = 0;
	*r_initial = p_source.start_pose;
	if (p_source.has_start_pose) {
		return "room.yaml's initial pose at frame 0";
	}
	for (size_t first = 0; first < reader.rgbd_count() && !p_truth.is_empty(); first++) {
		std::string error;
		const double t_s = reader.get_rgbd_ref(first).rgb.timestamp_s;
		if (p_truth.pose_at(t_s, r_initial, &error)) {
			*r_first = first;
			char text[96];
			std::snprintf(text, sizeof(text), "the ground-truth pose of frame %zu (t = %.4f s)", first, t_s);
			return text;
		}
	}
	*r_initial = Pose();
	return "the identity (no ground-truth pose at any frame: no ATE or RPE)";
}

void print_dense_header(const DenseSource &p_source, const DenseSlamOptions &p_slam, size_t p_total, size_t p_first, const std::string &p_start) {
	const RecordingReader &reader = *p_source.reader;
	const PinholeParams &rgb = p_source.camera;
	std::printf("roomprobe_bench slam %s\n", p_source.option.c_str());
	if (!p_source.skipped.empty()) {
		std::printf("  %s\n", p_source.skipped.c_str());
	}
	std::printf("  RGB-D %dx%d: %zu frames (%zu processed, from frame %zu), %zu issues; depth scale %.6f m per unit\n", rgb.width, rgb.height,
			reader.rgbd_count(), p_total, p_first, reader.get_issues().size(), reader.get_rig().depth_scale_m);
	std::printf("  intrinsics (%s): fx %.3f fy %.3f cx %.3f cy %.3f%s\n", p_source.camera_note.c_str(), rgb.fx, rgb.fy, rgb.cx, rgb.cy,
			has_pinhole_distortion(rgb) ? " (with distortion)" : "");
	print_issues(stdout, reader);
	std::printf("  start: %s\n", p_start.c_str());
	print_settings(p_slam);
	print_threads();
}

// Puts r_slam's tracking and integration on p_backend's device: where it runs, as the engine's note says it.
std::string set_backend(ComputeBackend p_backend, DenseSlam *r_slam) {
	std::string reason;
	const std::shared_ptr<ComputeDevice> device = shared_compute_device(p_backend, &reason);
	const std::string error = r_slam->set_compute(device);
	return compute_backend_note(p_backend, error.empty() ? device.get() : nullptr, device ? error : reason);
}

// The RGB-D frames from p_first on through SLAM; the frames processed (r_failed: unreadable).
size_t process_frames(const DenseSource &p_source, size_t p_first, size_t p_total, DenseSlam *r_slam, SlamFigures *r_figures,
		TrajectoryFile *r_trajectory_file, size_t *r_failed) {
	// The RGB-D stream alone, in time order, which is its index order (its timestamps increase):
	// event i is frame i, so the frames from p_first are the events from p_first.
	PlayerOptions options;
	options.fisheye = false;
	options.max_rgbd_frames = p_first + p_total;
	const RecordingPlayer player(p_source.reader, options);
	size_t done = 0;
	for (size_t e = p_first; e < player.events().size(); e++) {
		const SourceFrame frame = player.read(e);
		if (!frame.ok) {
			std::fprintf(stderr, "roomprobe_bench: %s (frame skipped)\n", frame.error.c_str());
			(*r_failed)++;
			continue;
		}
		const DenseSlamFrame result = r_slam->process(frame.rgbd);
		record_timings(result.timings, result.integrated, r_figures);
		record_state(result.tracking.state, r_figures);
		// The reported pose (the held one when Lost), as the application would use it.
		record_pose(frame.rgbd.timestamp_s, result.tracking.world_from_camera, r_figures);
		r_trajectory_file->add(frame.rgbd.timestamp_s, result.tracking.world_from_camera, result.tracking.state, result.tracking.reason);
		done++;
	}
	return done;
}

Accuracy print_dense_results(const DenseSource &p_source, const SlamFigures &p_figures, const Trajectory &p_truth, const DenseSlam &p_slam, size_t p_done,
		size_t p_failed) {
	const PinholeParams &rgb = p_source.camera;
	std::printf("  processed %zu frames, %zu unreadable\n\n", p_done, p_failed);
	print_table_header("per-stage timings, ms (paper: Table 1, for reference)");
	print_slam_rows(p_figures, "");
	std::printf("  time per frame (DenseSlam::process, median): %.2f ms; tracking + integration median %.2f ms\n", p_figures.process.median(),
			p_figures.track_integrate.median());
	if (p_source.synthetic) {
		print_slam_target(p_figures, rgb.width, rgb.height);
	}
	std::printf("\n");
	const Accuracy accuracy = print_accuracy(p_figures.reported, p_truth, p_figures, p_source.synthetic, "tracked RGB-D poses, the held pose when lost");
	std::printf("\n");
	print_memory(p_slam.volume().stats());
	return accuracy;
}

void print_dense_summary(const DenseSource &p_source, const SlamFigures &p_figures, const Accuracy &p_accuracy, size_t p_done, const std::string &p_backend) {
	std::printf("summary: mode=%s frames=%zu track_ms_p50=%.2f integrate_ms_p50=%.2f slam_ms_p50=%.2f track_integrate_ms_p50=%.2f %s %s good=%d "
				"poor=%d lost=%d\n",
			p_source.mode, p_done, p_figures.track.median(), p_figures.integrate.median(), p_figures.process.median(), p_figures.track_integrate.median(),
			accuracy_summary(p_accuracy).c_str(), p_backend.c_str(), p_figures.good, p_figures.poor, p_figures.lost);
}

// Dense SLAM over a dataset the caller opened into p_reader (--tum, --7scenes): the error of
// opening, or the benchmark.
int bench_dataset(const Arguments &p_args, const RecordingStatus &p_opened, const char *p_mode, const std::string &p_folder,
		std::shared_ptr<const RecordingReader> p_reader, DenseSource p_source) {
	if (!p_opened.ok) {
		std::fprintf(stderr, "roomprobe_bench: --%s: %s\n", p_mode, p_opened.error.c_str());
		return 1;
	}
	p_source.mode = p_mode;
	p_source.option = std::string("--") + p_mode + " " + p_folder;
	p_source.camera = p_reader->get_rig().rgb;
	p_source.reader = std::move(p_reader);
	return bench_dense(p_args, p_source);
}

} // namespace

int bench_dense(const Arguments &p_args, const DenseSource &p_source) {
	const RecordingReader &reader = *p_source.reader;
	const char *option = p_source.option.c_str();
	if (reader.rgbd_count() == 0) {
		std::fprintf(stderr, "roomprobe_bench: %s: no usable RGB-D frames\n", option);
		print_issues(stderr, reader);
		return 1;
	}
	const Trajectory &truth = reader.ground_truth_trajectory(RecordingStream::Rgbd);
	size_t first = 0;
	Pose initial;
	const std::string start = find_start(p_source, truth, &first, &initial);
	DenseSlam slam(p_args.slam);
	const std::string error = slam.configure(p_source.camera, initial);
	if (!error.empty()) {
		std::fprintf(stderr, "roomprobe_bench: %s: %s\n", option, error.c_str());
		return 1;
	}
	const size_t available = reader.rgbd_count() - first;
	const size_t total = p_args.frames > 0 ? std::min(available, size_t(p_args.frames)) : available;
	print_dense_header(p_source, p_args.slam, total, first, start);
	std::printf("  backend (tracking): %s\n", set_backend(p_args.backend, &slam).c_str());
	TrajectoryFile trajectory_file;
	if (!trajectory_file.open(p_args.save_trajectory, "slam " + p_source.option,
				p_source.has_start_pose ? "the room's (room.yaml's initial pose)" : "the ground truth's (SLAM starts at its pose of the first frame it covers)")) {
		return 1;
	}
	SlamFigures figures;
	size_t failed = 0;
	const size_t done = process_frames(p_source, first, total, &slam, &figures, &trajectory_file, &failed);
	if (done == 0) {
		std::fprintf(stderr, "roomprobe_bench: %s: no RGB-D frame could be read\n", option);
		return 1;
	}
	const Accuracy accuracy = print_dense_results(p_source, figures, truth, slam, done, failed);
	trajectory_file.close(p_args.save_trajectory);
	const std::string problem = slam.compute_problem();
	if (!problem.empty() && p_args.backend != ComputeBackend::Cpu) {
		std::printf("  backend: %s\n", problem.c_str());
	}
	print_device_batches(p_args.backend, done);
	print_dense_summary(p_source, figures, accuracy, done, backend_summary(p_args.backend, slam.tracks_on_gpu() && slam.integrates_on_gpu()));
	return 0;
}

int bench_tum(const Arguments &p_args) {
	TumDatasetOptions options;
	TumCamera camera = TumCamera::RosDefault;
	const bool named = tum_camera_from_folder_name(p_args.tum, &camera);
	DenseSource source;
	source.camera_note = !named ? "ROS default: the folder name gives no freiburg1/2/3"
			: camera == TumCamera::Freiburg1		   ? "Freiburg1"
			: camera == TumCamera::Freiburg2		   ? "Freiburg2"
													   : "Freiburg3";
	std::string note;
	if (!camera_from_arguments(p_args, tum_camera_intrinsics(camera), &options.rgb, &note)) {
		return 1;
	}
	source.camera_note = note.empty() ? source.camera_note : note;
	auto reader = std::make_shared<RecordingReader>();
	const RecordingStatus opened = open_tum_dataset(p_args.tum, reader.get(), options);
	return bench_dataset(p_args, opened, "tum", p_args.tum, std::move(reader), source);
}

int bench_7scenes(const Arguments &p_args) {
	FramesDatasetOptions options;
	DenseSource source;
	source.camera_note = "camera-intrinsics.txt";
	PinholeParams from_images; // width and height 0: the images'
	std::string note;
	if (!camera_from_arguments(p_args, from_images, &options.intrinsics, &note)) {
		return 1;
	}
	if (!note.empty()) {
		options.override_intrinsics = true;
		source.camera_note = note;
	}
	auto reader = std::make_shared<RecordingReader>();
	const RecordingStatus opened = open_frames_dataset(p_args.seven_scenes, reader.get(), options);
	return bench_dataset(p_args, opened, "7scenes", p_args.seven_scenes, std::move(reader), source);
}

} // namespace roomprobe::bench
