#pragma once
// The one check of a path a user names as an input (issue #38): before a file is read or a folder
// listed, what is there is looked at, and a message says what is wrong with it. /dev/zero given as
// a panorama was once called "no such file"; a named pipe would have blocked the reader.
//
// Every function returns "" or "PATH: what is wrong", and never throws.

#include <string>

namespace roomprobe {

// What is at p_path, through links, for messages: "a regular file", "a folder", "a character
// device", "a block device", "a named pipe (FIFO)", "a socket", "a link to a missing file",
// "missing", or "not reachable (Permission denied)".
std::string describe_path(const std::string &p_path);

// "" when p_path is a regular file (through links); otherwise "PATH: " and: p_missing when
// nothing is there ("missing", "no such rig file"), "a folder, not a file", "not a regular file
// (a character device)", "a link to a missing file (TARGET)".
std::string input_file_problem(const std::string &p_path, const std::string &p_missing = "missing");

// "" when p_path is a folder (through links); otherwise "PATH: " and p_missing ("no such
// recording folder") or "not a folder (a regular file)", "not a folder (a character device)".
std::string input_folder_problem(const std::string &p_path, const std::string &p_missing = "no such folder");

} // namespace roomprobe
