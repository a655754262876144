// fixed/input_file.h — every file a user hands the program to read (a scene, a machine
// profile, a ledger's CSV, a report to calibrate from, a PNG), opened one way.
//
// Only a regular file is read: a directory would read as empty or as "not valid JSON", and a
// FIFO or a device (/dev/zero, /dev/stdin) may block or never end, so its kind is checked
// before it is opened. Its size is checked before any byte is read. It lives in fixed/, the
// bottom of the dependency chain, so the machine profile reader (bitserial/) and every
// reader in hosts/ share it (docs/errors.md, "Input files").
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace zephyr {

// How a message names the file: `the` ("the scene file") and `an` ("an NFF scene file").
struct InputKind {
  const char* the;
  const char* an;
};

// `path` as a message shows it: bytes outside printable ASCII as \xNN (a NUL would cut the
// message, a byte-order mark would be invisible); never shortened.
std::string PrintablePath(std::string_view path);

// Checks that `path` names a regular file of at most `maxBytes` bytes without opening it.
// UserError "PATH: cannot open the scene file (no such file)", "PATH: is a directory,
// expected an NFF scene file", "PATH: is not a regular file (a device, pipe or socket),
// expected ...", "PATH: the scene file has N bytes, more than the M MiB it may have", or the
// system's own reason (a link loop, a folder that may not be searched). Returns the size.
std::uintmax_t CheckInputFile(const std::string& path, InputKind kind, std::uintmax_t maxBytes);

// The whole of `path` after CheckInputFile; UserError also when it cannot be read.
std::string ReadInputFile(const std::string& path, InputKind kind, std::uintmax_t maxBytes);

// Refuses a NUL byte in `text`, the text of `file` (a JSON profile or report): no text format
// read here holds one, and nlohmann's parser ends its input at the first NUL, so whatever
// follows it would be ignored without a word. UserError "FILE:LINE:COLUMN: a NUL byte (a text
// file holds none)", at the first one.
void RefuseNulBytes(std::string_view text, const std::string& file);

}  // namespace zephyr
