#include "project_paths.h"

#include <io/zip_limits.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <vector>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

using namespace godot;
namespace fs = std::filesystem;

namespace roomprobe {

namespace {

const char *const kUnpacked = "user://roomprobe/unpacked/";
const char *const kStamp = ".roomprobe-unpacked"; // written last, before the rename: a half-unpacked folder is not used

bool ends_with_zip(const std::string &p_path) {
	if (p_path.size() < 4) {
		return false;
	}
	std::string tail = p_path.substr(p_path.size() - 4);
	for (char &c : tail) {
		c = char(std::tolower(static_cast<unsigned char>(c)));
	}
	return tail == ".zip";
}

// An entry that would land outside the folder it is unpacked into ("zip slip") is refused.
bool safe_entry(const std::string &p_name) {
	if (p_name.empty() || p_name[0] == '/' || p_name.find('\\') != std::string::npos || p_name.find(':') != std::string::npos) {
		return false;
	}
	for (const auto &part : fs::path(p_name)) {
		if (part == "..") {
			return false;
		}
	}
	return true;
}

// Writes p_bytes to p_path (replacing it); false when the file cannot be written.
bool write_bytes(const fs::path &p_path, const PackedByteArray &p_bytes) {
	std::ofstream file(p_path, std::ios::binary | std::ios::trunc);
	file.write(reinterpret_cast<const char *>(p_bytes.ptr()), std::streamsize(p_bytes.size()));
	file.close();
	return bool(file);
}

bool write_text(const fs::path &p_path, const std::string &p_text) {
	std::ofstream file(p_path, std::ios::binary | std::ios::trunc);
	file << p_text;
	file.close();
	return bool(file);
}

std::string globalize(const std::string &p_path) {
	return ProjectSettings::get_singleton()->globalize_path(String(p_path.c_str())).utf8_string();
}

// The entries of the zip at p_path (in a pack too) as its table of contents declares them, read
// without inflating anything; "" or what is wrong, naming the zip.
std::string zip_entries(const String &p_path, std::vector<ZipEntryInfo> *r_entries) {
	const std::string path = p_path.utf8_string();
	Ref<FileAccess> file = FileAccess::open(p_path, FileAccess::READ);
	if (file.is_null()) {
		return path + ": cannot be read";
	}
	const ZipReadAt read = [&](uint64_t p_offset, size_t p_size, uint8_t *p_buffer) -> size_t {
		file->seek(p_offset);
		const PackedByteArray bytes = file->get_buffer(int64_t(p_size));
		const size_t got = std::min(size_t(bytes.size()), p_size);
		if (got > 0) {
			std::memcpy(p_buffer, bytes.ptr(), got);
		}
		return got;
	};
	return list_zip_entries(path, file->get_length(), read, r_entries);
}

// Held while a zip is unpacked into the folder p_folder (user://roomprobe/unpacked/): one unpacker
// at a time (another thread, another process), so that none removes or renames another's
// half-written folder. The folder itself is locked, so no lock file is left behind. Released on
// destruction, and by the system when the process dies.
class UnpackLock {
public:
	explicit UnpackLock(const std::string &p_folder) {
		fd = ::open(p_folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
		if (fd >= 0 && ::flock(fd, LOCK_EX) != 0) {
			::close(fd);
			fd = -1;
		}
	}
	~UnpackLock() {
		if (fd >= 0) {
			::close(fd);
		}
	}
	UnpackLock(const UnpackLock &) = delete;
	UnpackLock &operator=(const UnpackLock &) = delete;
	bool held() const { return fd >= 0; }

private:
	int fd = -1;
};

// Unpacked recordings not used for this long are removed when another zip is unpacked or used: each
// version of a zipped recording unpacks beside the others (by its MD5), so without this user://
// would keep every version ever played.
constexpr std::chrono::hours UNPACKED_KEPT_UNUSED(24 * 7);

// Under the unpack lock (no other unpacker writes meanwhile): removes half-unpacked folders
// (NAME.partial, or without the stamp: a killed or failed unpack) and unpacked ones whose stamp
// (touched at every use) is older than UNPACKED_KEPT_UNUSED, except p_keep. Best effort: a folder
// that cannot be removed stays.
void prune_unpacked(const fs::path &p_folder, const fs::path &p_keep) {
	std::error_code ec;
	const auto now = fs::file_time_type::clock::now();
	for (const auto &entry : fs::directory_iterator(p_folder, ec)) {
		if (entry.path() == p_keep || !entry.is_directory(ec)) {
			continue;
		}
		const fs::path stamp = entry.path() / kStamp;
		const bool whole = entry.path().extension() != ".partial" && fs::exists(stamp, ec);
		if (!whole || now - fs::last_write_time(stamp, ec) > UNPACKED_KEPT_UNUSED) {
			std::error_code ignored;
			fs::remove_all(entry.path(), ignored);
		}
	}
}

// The folder a zip unpacks into, and inside it the one top-level folder when there is just one.
//
// Issue #38: a zip bomb inflated without limit into user://. Before anything is inflated, the
// entries' declared sizes are checked against ZipLimits and the disk's free space (io/zip_limits.h),
// and each entry must then inflate to exactly its declared size. The folder is unpacked as
// NAME.partial, stamped last, and renamed into place only when whole: a folder at the target is
// complete, and a half-unpacked one (a full disk, a damaged entry, a killed process) is never used.
std::string unpack_zip(const String &p_path, std::string *r_error) {
	const std::string path = p_path.utf8_string();
	const std::string md5 = FileAccess::get_md5(p_path).utf8_string();
	if (md5.empty()) {
		*r_error = path + ": cannot be read (missing, or not a file)";
		return "";
	}
	std::string stem = fs::path(path).stem().string();
	const std::string target = globalize(kUnpacked + stem + "-" + md5.substr(0, 12));
	std::error_code ec;
	std::set<std::string> top;
	bool top_files = false;
	fs::create_directories(fs::path(target).parent_path(), ec);
	const UnpackLock lock(fs::path(target).parent_path().string());
	if (!lock.held()) {
		*r_error = path + ": cannot unpack into " + fs::path(target).parent_path().string() + " (" + std::strerror(errno) + ")";
		return "";
	}
	prune_unpacked(fs::path(target).parent_path(), target);
	if (!fs::exists(fs::path(target) / kStamp, ec)) {
		std::vector<ZipEntryInfo> entries;
		std::string problem = zip_entries(p_path, &entries);
		if (problem.empty()) {
			const fs::space_info space = fs::space(fs::path(target).parent_path(), ec);
			problem = check_zip_limits(path, entries, ZipLimits(), ec ? UINT64_MAX : uint64_t(space.available));
		}
		if (!problem.empty()) {
			*r_error = problem;
			return "";
		}
		Ref<ZIPReader> zip;
		zip.instantiate();
		if (zip->open(p_path) != OK) {
			*r_error = path + ": not a readable zip archive";
			return "";
		}
		const std::string partial = target + ".partial";
		fs::remove_all(partial, ec);
		fs::create_directories(partial, ec);
		if (ec) {
			*r_error = path + ": cannot unpack into " + partial + " (" + ec.message() + ")";
			return "";
		}
		auto fail = [&](const std::string &p_error) {
			*r_error = p_error;
			zip->close();
			std::error_code ignored;
			fs::remove_all(partial, ignored);
			return std::string();
		};
		for (const ZipEntryInfo &entry : entries) {
			const std::string &name = entry.name;
			if (!safe_entry(name)) {
				return fail(path + ": entry '" + name + "' would land outside the folder it is unpacked into; refused");
			}
			const fs::path out = fs::path(partial) / name;
			if (name.back() == '/') {
				fs::create_directories(out, ec);
				if (ec) {
					return fail(path + ": cannot create " + out.string() + " while unpacking (" + ec.message() + ")");
				}
				continue;
			}
			fs::create_directories(out.parent_path(), ec);
			// ZIPReader inflates no more than the entry declares, and returns nothing on a CRC or
			// data error: anything but the declared size is a damaged entry, never a short file.
			const PackedByteArray bytes = zip->read_file(String(name));
			if (uint64_t(bytes.size()) != entry.uncompressed_bytes) {
				return fail(path + ": entry '" + name + "' is damaged: " + std::to_string(bytes.size()) + " of its " +
						std::to_string(entry.uncompressed_bytes) + " bytes could be inflated; nothing unpacked");
			}
			if (ec || !write_bytes(out, bytes)) {
				return fail(path + ": cannot write " + out.string() + " while unpacking (disk full?); nothing unpacked");
			}
		}
		zip->close();
		// The stamp last, inside, then one rename: a folder at the target is whole.
		if (!write_text(fs::path(partial) / kStamp, path + "\n")) {
			return fail(path + ": cannot write " + (fs::path(partial) / kStamp).string() + " while unpacking (disk full?); nothing unpacked");
		}
		fs::remove_all(target, ec); // an earlier unpack without its stamp: never used
		fs::rename(partial, target, ec);
		if (ec) {
			*r_error = path + ": cannot move the unpacked folder into place (" + ec.message() + ")";
			fs::remove_all(partial, ec);
			return "";
		}
	}
	fs::last_write_time(fs::path(target) / kStamp, fs::file_time_type::clock::now(), ec); // used now: kept another UNPACKED_KEPT_UNUSED
	for (const auto &entry : fs::directory_iterator(target, ec)) {
		if (entry.path().filename() == kStamp) {
			continue;
		}
		if (entry.is_directory()) {
			top.insert(entry.path().string());
		} else {
			top_files = true;
		}
	}
	return top.size() == 1 && !top_files ? *top.begin() : target;
}

} // namespace

std::string disk_path_for(const String &p_path, std::string *r_error) {
	const std::string path = p_path.utf8_string();
	r_error->clear();
	if (path.empty()) {
		return "";
	}
	if (ends_with_zip(path)) {
		return unpack_zip(p_path, r_error);
	}
	const bool res = p_path.begins_with("res://");
	if (!res && !p_path.begins_with("user://")) {
		return path;
	}
	const std::string global = globalize(path);
	std::error_code ec;
	if (!res || fs::exists(global, ec)) {
		return global;
	}
	// res:// that is not on disk: inside an exported app's pack.
	if (FileAccess::file_exists(p_path)) {
		const std::string copy = globalize(kUnpacked + std::string("files/") + path.substr(6));
		fs::create_directories(fs::path(copy).parent_path(), ec);
		if (!write_bytes(copy, FileAccess::get_file_as_bytes(p_path))) {
			*r_error = path + ": cannot copy it out of the pack to " + copy;
			return "";
		}
		return copy;
	}
	if (DirAccess::dir_exists_absolute(p_path)) {
		*r_error = path + ": a folder inside the exported pack, where Godot keeps a recording's PNG frames only as imported "
						  "textures; zip the recording folder and give res://....zip instead (docs/addon.md)";
		return "";
	}
	return global; // not anywhere: the core says it is missing, naming the path
}

} // namespace roomprobe
