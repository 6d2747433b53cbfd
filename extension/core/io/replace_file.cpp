#include "replace_file.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

namespace roomprobe {

namespace fs = std::filesystem;

namespace {

std::atomic<unsigned> temp_count{ 0 };

// Hidden, and unique to this process and call. The target's name is cut so that the whole stays
// within a file name's 255 bytes.
fs::path temp_beside(const fs::path &p_file) {
	const std::string name = p_file.filename().string().substr(0, 200);
	return p_file.parent_path() / ("." + name + "." + std::to_string(::getpid()) + "-" + std::to_string(temp_count++) + ".tmp");
}

// Through a link, the file it names: the link stays a link.
fs::path through_link(const std::string &p_path) {
	std::error_code ec;
	if (!fs::is_symlink(p_path, ec) || !fs::exists(p_path, ec)) {
		return p_path;
	}
	const fs::path file = fs::canonical(p_path, ec);
	return ec ? fs::path(p_path) : file;
}

std::string system_error(const std::string &p_path, const char *p_what, int p_errno) {
	return p_path + ": " + p_what + ": " + std::strerror(p_errno);
}

} // namespace

std::string check_replaceable(const std::string &p_path) {
	std::error_code ec;
	const fs::file_status status = fs::status(p_path, ec);
	if (status.type() == fs::file_type::not_found) {
		return "";
	}
	if (ec) {
		return p_path + ": cannot be looked at: " + ec.message();
	}
	if (fs::is_directory(status)) {
		return p_path + ": is a folder, not a file";
	}
	if (!fs::is_regular_file(status)) {
		return p_path + ": is not a regular file (a device, a pipe or a socket), so it is never written, replaced or removed";
	}
	return "";
}

std::string FileReplacement::begin(const std::string &p_target) {
	discard();
	target = p_target;
	const std::string problem = check_replaceable(p_target);
	if (!problem.empty()) {
		return problem;
	}
	const fs::path file = through_link(p_target);
	for (int attempt = 0; attempt < 16; attempt++) {
		const fs::path name = temp_beside(file);
		// O_EXCL: never a file someone else made. 0666 less the umask, as a plain create gives.
		const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
		if (fd >= 0) {
			::close(fd);
			temp = name.string();
			replaced = file.string();
			return "";
		}
		if (errno != EEXIST) {
			return system_error(p_target, "cannot be opened for writing", errno);
		}
	}
	return p_target + ": cannot be opened for writing: no unused temporary name beside it";
}

std::string FileReplacement::commit() {
	if (temp.empty()) {
		return target + ": nothing was written";
	}
	// Again: the target may have become a folder or a device since begin().
	std::string problem = check_replaceable(replaced);
	if (problem.empty() && std::rename(temp.c_str(), replaced.c_str()) != 0) {
		problem = system_error(target, "could not be written", errno);
	}
	if (!problem.empty()) {
		discard();
		return problem;
	}
	temp.clear();
	return "";
}

void FileReplacement::discard() {
	if (!temp.empty()) {
		::unlink(temp.c_str());
		temp.clear();
	}
}

std::string replace_file(const std::string &p_path, const void *p_bytes, size_t p_size) {
	FileReplacement replacement;
	const std::string error = replacement.begin(p_path);
	if (!error.empty()) {
		return error;
	}
	// stdio rather than a stream: a full disk is named by errno ("No space left on device").
	std::FILE *file = std::fopen(replacement.temp_path().c_str(), "wb");
	if (file == nullptr) {
		return system_error(p_path, "cannot be opened for writing", errno);
	}
	const bool written = std::fwrite(p_bytes, 1, p_size, file) == p_size;
	const int write_errno = errno;
	const bool closed = std::fclose(file) == 0;
	if (!written || !closed) {
		return system_error(p_path, "could not be written", written ? errno : write_errno); // the temporary file goes with replacement
	}
	return replacement.commit();
}

} // namespace roomprobe
