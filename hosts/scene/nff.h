// hosts/scene/nff.h — reading and writing NFF, Eric Haines' Neutral File Format, as the
// Standard Procedural Databases write it, plus our `transform` extension
// (docs/scene-format.md).
//
// Errors are collected, each as "file:line:column: what was expected", and reported once:
// ParseNff returns them to the caller (tests, the fuzz target); ReadNffFile throws one
// UserError listing them all.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hosts/scene/scene.h"

namespace zephyr {

// Limits that make a scene "absurd" rather than merely big.
inline constexpr int kMaxResolution = 16384;  // per side
inline constexpr int kMaxPolygonVertices = 1 << 20;
// The largest scene file ReadNffFile reads: 64 MiB, over a million SPD objects, far more
// than an exhaustive tracer (every ray against every object) can render.
inline constexpr std::uintmax_t kMaxSceneBytes = std::uintmax_t(64) << 20;

// How many error messages a parse keeps (the first, in file order) and after how many
// errors it stops reading, as compilers do (clang's -ferror-limit): a file of 33 million
// bad lines costs milliseconds and a few kilobytes, not minutes and gigabytes.
inline constexpr std::size_t kKeptNffErrors = 20;
inline constexpr std::size_t kMaxNffErrors = 1000;

// The errors of one parse: every error is counted, the first kKeptNffErrors are kept as
// "file:line:column: what was expected".
struct NffErrors {
  std::vector<std::string> messages;  // at most kKeptNffErrors
  std::size_t count = 0;              // all errors found (at most kMaxNffErrors)
  int stoppedAtLine = 0;              // > 0: reading stopped there, at kMaxNffErrors errors
  // "N errors in scene:", the kept messages, "... and M more", where reading stopped.
  std::string Summary() const;
};

// Parses NFF text. On success returns the scene and leaves errors empty; otherwise returns
// nullopt with the errors found (count >= 1).
std::optional<Scene> ParseNff(std::string_view text, const std::string& fileName,
                              NffErrors& errors);
// The same, keeping only the messages (the first kKeptNffErrors).
std::optional<Scene> ParseNff(std::string_view text, const std::string& fileName,
                              std::vector<std::string>& errors);

// ParseNff, throwing a UserError with NffErrors::Summary().
Scene ParseNffOrThrow(std::string_view text, const std::string& fileName);

// Reads a file; a missing or unreadable file, a directory, anything but a regular file, and
// a file over kMaxSceneBytes are UserErrors too.
Scene ReadNffFile(const std::string& path);

// Writes a scene as NFF (with `transform` lines where objects have one). Numbers are
// written with 17 significant digits, so ParseNff(WriteNff(s)) reproduces s exactly.
std::string WriteNff(const Scene& scene);

}  // namespace zephyr
