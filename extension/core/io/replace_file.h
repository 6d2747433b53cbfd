#pragma once
// Output files written whole or not at all (issue #38). A file is written beside its target under
// a unique name and renamed over the target only once complete: a failed write leaves the target
// as it was, and the only file ever removed is the temporary one made here. A target that exists
// and is not a regular file (a folder, a device such as /dev/full, a pipe) is refused: it is never
// written to, replaced or removed.
//
// Every function returns "" or what is wrong, naming the target, and never throws.

#include <cstddef>
#include <string>

namespace roomprobe {

// "" when p_path may be written: it does not exist, or it is a regular file (through links).
std::string check_replaceable(const std::string &p_path);

// One replacement of a file: begin() makes an empty temporary file beside the target, the caller
// writes it by temp_path(), and commit() renames it over the target. Destroyed or begun again
// before commit(), it removes its temporary file.
class FileReplacement {
public:
	FileReplacement() = default;
	FileReplacement(const FileReplacement &) = delete;
	FileReplacement &operator=(const FileReplacement &) = delete;
	~FileReplacement() { discard(); }

	std::string begin(const std::string &p_target);
	const std::string &temp_path() const { return temp; }
	std::string commit();
	// Removes the temporary file, and only it.
	void discard();

private:
	std::string target; // as given, for the messages
	std::string replaced; // the file renamed over: through a link, the file it names
	std::string temp;
};

// p_size bytes from p_bytes as the whole of p_path. Errors give the system's reason ("No space
// left on device").
std::string replace_file(const std::string &p_path, const void *p_bytes, size_t p_size);

} // namespace roomprobe
