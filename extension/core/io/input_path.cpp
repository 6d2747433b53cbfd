#include "input_path.h"

#include <filesystem>
#include <system_error>

namespace fs = std::filesystem;

namespace roomprobe {

namespace {

// The status through links; an error other than "nothing there" in r_error.
fs::file_status status_of(const std::string &p_path, std::error_code *r_error) {
	std::error_code ec;
	const fs::file_status status = fs::status(p_path, ec);
	if (ec && status.type() != fs::file_type::not_found) {
		*r_error = ec;
	}
	return status;
}

std::string kind_name(fs::file_type p_type) {
	switch (p_type) {
		case fs::file_type::regular:
			return "a regular file";
		case fs::file_type::directory:
			return "a folder";
		case fs::file_type::character:
			return "a character device";
		case fs::file_type::block:
			return "a block device";
		case fs::file_type::fifo:
			return "a named pipe (FIFO)";
		case fs::file_type::socket:
			return "a socket";
		case fs::file_type::not_found:
			return "missing";
		default:
			return "neither a file nor a folder";
	}
}

// A link whose target is missing, or "".
std::string dangling_link(const std::string &p_path) {
	std::error_code ec;
	if (!fs::is_symlink(fs::symlink_status(p_path, ec))) {
		return "";
	}
	const fs::path target = fs::read_symlink(p_path, ec);
	return "a link to a missing file (" + (ec ? std::string("?") : target.string()) + ")";
}

} // namespace

std::string describe_path(const std::string &p_path) {
	std::error_code error;
	const fs::file_status status = status_of(p_path, &error);
	if (error) {
		return "not reachable (" + error.message() + ")";
	}
	if (status.type() == fs::file_type::not_found) {
		const std::string link = dangling_link(p_path);
		return link.empty() ? "missing" : link;
	}
	return kind_name(status.type());
}

std::string input_file_problem(const std::string &p_path, const std::string &p_missing) {
	std::error_code error;
	const fs::file_status status = status_of(p_path, &error);
	if (error) {
		return p_path + ": cannot be looked at (" + error.message() + ")";
	}
	switch (status.type()) {
		case fs::file_type::regular:
			return "";
		case fs::file_type::directory:
			return p_path + ": a folder, not a file";
		case fs::file_type::not_found: {
			const std::string link = dangling_link(p_path);
			return p_path + ": " + (link.empty() ? p_missing : link);
		}
		default:
			return p_path + ": not a regular file (" + kind_name(status.type()) + ")";
	}
}

std::string input_folder_problem(const std::string &p_path, const std::string &p_missing) {
	std::error_code error;
	const fs::file_status status = status_of(p_path, &error);
	if (error) {
		return p_path + ": cannot be looked at (" + error.message() + ")";
	}
	switch (status.type()) {
		case fs::file_type::directory:
			return "";
		case fs::file_type::not_found: {
			const std::string link = dangling_link(p_path);
			return p_path + ": " + (link.empty() ? p_missing : link);
		}
		default:
			return p_path + ": not a folder (" + kind_name(status.type()) + ")";
	}
}

} // namespace roomprobe
