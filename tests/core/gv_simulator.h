#pragma once
// Aravis' GigE Vision simulator (arv-fake-gv-camera-0.8, aravis-tools) as a child process on the
// loopback interface, for the tests of a camera that vanishes and comes back.

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

inline const char *const GV_SIMULATOR = "arv-fake-gv-camera-0.8";

inline std::string find_on_path(const std::string &p_program) {
	const char *path = std::getenv("PATH");
	std::string dirs = path ? path : "/usr/bin:/bin";
	size_t start = 0;
	while (start <= dirs.size()) {
		const size_t end = std::min(dirs.find(':', start), dirs.size());
		const std::filesystem::path candidate = std::filesystem::path(dirs.substr(start, end - start)) / p_program;
		if (access(candidate.c_str(), X_OK) == 0) {
			return candidate.string();
		}
		start = end + 1;
	}
	return "";
}

// Evaluated when the test registers, so that the skip shows in doctest's count.
inline bool gv_simulator_missing(const char *p_test) {
	const bool missing = find_on_path(GV_SIMULATOR).empty();
	if (missing) {
		std::fprintf(stderr, "skipping %s: %s (aravis-tools) is not on PATH\n", p_test, GV_SIMULATOR);
	}
	return missing;
}

// The GigE Vision simulator as a child process: killed and reaped when this
// goes, and killed by the kernel should the test program crash first.
class GvSimulator {
public:
	GvSimulator() {
		const std::string program = find_on_path(GV_SIMULATOR);
		char *const argv[] = { const_cast<char *>(program.c_str()), const_cast<char *>("-i"), const_cast<char *>("127.0.0.1"), nullptr };
		pid = fork();
		if (pid == 0) {
			// Only async-signal-safe calls between fork and exec.
			prctl(PR_SET_PDEATHSIG, SIGKILL);
			const int null_fd = open("/dev/null", O_WRONLY);
			dup2(null_fd, 1);
			dup2(null_fd, 2);
			execv(program.c_str(), argv);
			_exit(127);
		}
	}
	GvSimulator(const GvSimulator &) = delete;
	GvSimulator &operator=(const GvSimulator &) = delete;
	~GvSimulator() { kill(); }

	// False once it has exited, e.g. because another simulator holds the port.
	bool running() {
		return pid > 0 && waitpid(pid, nullptr, WNOHANG) == 0;
	}
	void kill() {
		if (pid > 0) {
			::kill(pid, SIGKILL);
			waitpid(pid, nullptr, 0);
			pid = -1;
		}
	}

private:
	pid_t pid = -1;
};


