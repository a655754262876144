#include "fixed/input_file.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "fixed/check.h"

namespace zephyr {

std::string PrintablePath(std::string_view path) {
  std::string out;
  for (const char ch : path) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (c >= 0x20 && c < 0x7f) {
      out += ch;
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  return out;
}

std::uintmax_t CheckInputFile(const std::string& path, InputKind kind, std::uintmax_t maxBytes) {
  namespace fs = std::filesystem;
  const std::string shown = PrintablePath(path);
  if (path.empty()) throw UserError(std::string("an empty path names no file, expected ") + kind.an);
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  // The system's own reason: a symbolic-link loop (ELOOP) or a directory that may not be
  // searched (EACCES) is not "no such file".
  if (ec && ec != std::errc::no_such_file_or_directory && ec != std::errc::not_a_directory)
    throw UserError(shown + ": cannot open " + kind.the + " (" + ec.message() + ")");
  if (ec || !fs::exists(status))
    throw UserError(shown + ": cannot open " + kind.the + " (no such file)");
  if (fs::is_directory(status))
    throw UserError(shown + ": is a directory, expected " + kind.an);
  if (!fs::is_regular_file(status))
    throw UserError(shown + ": is not a regular file (a device, pipe or socket), expected " +
                    kind.an);
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw UserError(shown + ": cannot read the size of " + kind.the);
  if (size > maxBytes) {
    const std::string limit = maxBytes >= (std::uintmax_t(1) << 20)
                                  ? std::to_string(maxBytes >> 20) + " MiB"
                                  : std::to_string(maxBytes) + " bytes";
    throw UserError(shown + ": " + kind.the + " has " + std::to_string(size) +
                    " bytes, more than the " + limit + " it may have");
  }
  return size;
}

std::string ReadInputFile(const std::string& path, InputKind kind, std::uintmax_t maxBytes) {
  const std::uintmax_t size = CheckInputFile(path, kind, maxBytes);
  const std::string shown = PrintablePath(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UserError(shown + ": cannot open " + kind.the);
  std::string text(size, '\0');
  in.read(text.data(), std::streamsize(size));
  if (in.gcount() != std::streamsize(size) || in.bad())
    throw UserError(shown + ": cannot read " + kind.the);
  return text;
}

void RefuseNulBytes(std::string_view text, const std::string& file) {
  const size_t at = text.find('\0');
  if (at == std::string_view::npos) return;
  size_t line = 1, column = 1;
  for (size_t i = 0; i < at; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  throw UserError(PrintablePath(file) + ":" + std::to_string(line) + ":" + std::to_string(column) +
                  ": a NUL byte (a text file holds none)");
}

}  // namespace zephyr
