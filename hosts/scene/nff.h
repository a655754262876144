// hosts/scene/nff.h — reading and writing NFF, Eric Haines' Neutral File Format, as the
// Standard Procedural Databases write it, plus our `transform` extension
// (docs/scene-format.md).
//
// Errors are collected, each as "file:line:column: what was expected", and reported once:
// ParseNff returns them to the caller (tests, the fuzz target); ReadNffFile throws one
// UserError listing them all.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hosts/scene/scene.h"

namespace zephyr {

// Limits that make a scene "absurd" rather than merely big.
inline constexpr int kMaxResolution = 16384;           // per side
inline constexpr int kMaxPolygonVertices = 1 << 20;
// The largest scene file ReadNffFile reads: 64 MiB, over a million SPD objects, far more
// than an exhaustive tracer (every ray against every object) can render.
inline constexpr std::uintmax_t kMaxSceneBytes = std::uintmax_t(64) << 20;

// Parses NFF text. On success returns the scene and leaves errors empty; otherwise returns
// nullopt with every error found (at least one).
std::optional<Scene> ParseNff(std::string_view text, const std::string& fileName,
                              std::vector<std::string>& errors);

// ParseNff, throwing a UserError that lists every error.
Scene ParseNffOrThrow(std::string_view text, const std::string& fileName);

// Reads a file; a missing or unreadable file, a directory, anything but a regular file, and
// a file over kMaxSceneBytes are UserErrors too.
Scene ReadNffFile(const std::string& path);

// Writes a scene as NFF (with `transform` lines where objects have one). Numbers are
// written with 17 significant digits, so ParseNff(WriteNff(s)) reproduces s exactly.
std::string WriteNff(const Scene& scene);

}  // namespace zephyr
