#include "project_paths.h"

#include <cctype>
#include <filesystem>
#include <fstream>
#include <set>

using namespace godot;
namespace fs = std::filesystem;

namespace roomprobe {

namespace {

const char *const kUnpacked = "user://roomprobe/unpacked/";
const char *const kStamp = ".roomprobe-unpacked"; // written last: a half-unpacked folder is not used

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

std::string globalize(const std::string &p_path) {
	return ProjectSettings::get_singleton()->globalize_path(String(p_path.c_str())).utf8_string();
}

// The folder a zip unpacks into, and inside it the one top-level folder when there is just one.
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
	if (!fs::exists(fs::path(target) / kStamp, ec)) {
		Ref<ZIPReader> zip;
		zip.instantiate();
		if (zip->open(p_path) != OK) {
			*r_error = path + ": not a readable zip archive";
			return "";
		}
		const PackedStringArray files = zip->get_files();
		const std::string partial = target + ".partial";
		fs::remove_all(partial, ec);
		fs::create_directories(partial, ec);
		if (ec) {
			*r_error = path + ": cannot unpack into " + partial + " (" + ec.message() + ")";
			return "";
		}
		for (int64_t i = 0; i < files.size(); ++i) {
			const std::string name = files[i].utf8_string();
			if (!safe_entry(name)) {
				*r_error = path + ": entry '" + name + "' would land outside the folder it is unpacked into; refused";
				fs::remove_all(partial, ec);
				return "";
			}
			const fs::path out = fs::path(partial) / name;
			if (name.back() == '/') {
				fs::create_directories(out, ec);
				continue;
			}
			fs::create_directories(out.parent_path(), ec);
			if (!write_bytes(out, zip->read_file(files[i]))) {
				*r_error = path + ": cannot write " + out.string() + " while unpacking (disk full?)";
				fs::remove_all(partial, ec);
				return "";
			}
		}
		zip->close();
		fs::remove_all(target, ec);
		fs::rename(partial, target, ec);
		if (ec) {
			*r_error = path + ": cannot move the unpacked folder into place (" + ec.message() + ")";
			return "";
		}
		std::ofstream(fs::path(target) / kStamp) << path << "\n";
	}
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
