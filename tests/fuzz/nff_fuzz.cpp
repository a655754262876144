// libFuzzer target for the NFF reader, the host tracer, the SIMD planner and the output
// pre-flight: any input must give a scene or a list of errors, a scene must trace and plan
// or raise a UserError (a clear message), and the input's first line, taken as an output
// path inside a scratch directory that holds one of every kind of file (a regular file,
// a directory, a FIFO, a device node where mknod is permitted, a symbolic-link loop, a
// dangling link), must pass CheckOutputs or raise a UserError — never a crash, an
// internal-check abort, a hang or a sanitizer report, and never a file left or replaced.
// Built by `make fuzz` with clang, -fsanitize=fuzzer,address,undefined; seeds come from
// tests/fuzz/corpus/.
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "fixed/check.h"
#include "hosts/io/output_file.h"
#include "hosts/scene/nff.h"
#include "hosts/simd/plan.h"
#include "hosts/trace/tracer.h"

namespace {

// The scratch directory, made once: one of every kind of thing an output path can name.
const std::filesystem::path& Scratch() {
  static const std::filesystem::path dir = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "zephyr-fuzz-XXXXXX").string();
    const std::filesystem::path d = ::mkdtemp(pattern.data());
    std::ofstream(d / "scene.nff") << "v\n";
    std::filesystem::create_directory(d / "dir");
    ::mkfifo((d / "fifo").c_str(), 0600);
    ::mknod((d / "dev").c_str(), S_IFCHR | 0600,
            makedev(1, 7));  // /dev/full's numbers; may be refused
    std::filesystem::create_symlink(d / "loop-b", d / "loop-a");
    std::filesystem::create_symlink(d / "loop-a", d / "loop-b");
    std::filesystem::create_symlink(d / "missing", d / "dangling");
    std::atexit([] { std::filesystem::remove_all(Scratch()); });
    return d;
  }();
  return dir;
}

// The input's first line as a path inside the scratch directory: no leading '/', no '..'
// component (the pre-flight may only probe inside it), at most 200 bytes.
std::string OutputPathOf(std::string_view text) {
  std::string line(text.substr(0, std::min<size_t>(text.find('\n'), 200)));
  std::string safe;
  for (size_t start = 0; start <= line.size();) {
    const size_t end = std::min(line.find('/', start), line.size());
    const std::string part = line.substr(start, end - start);
    if (!part.empty() && part != ".." && part.find('\0') == std::string::npos)
      safe += (safe.empty() ? "" : "/") + part;
    start = end + 1;
  }
  return (Scratch() / safe).string();
}

void CheckThePreflight(std::string_view text) {
  const std::string out = OutputPathOf(text);
  const size_t before = std::distance(std::filesystem::directory_iterator(Scratch()), {});
  try {
    zephyr::CheckOutputs({{"--out", out}, {"--report", out + ".json"}},
                         {{"the scene file", (Scratch() / "scene.nff").string()}});
  } catch (const zephyr::UserError&) {
  }
  // The probe leaves nothing behind, and every special file is still what it was.
  if (std::distance(std::filesystem::directory_iterator(Scratch()), {}) != ptrdiff_t(before))
    __builtin_trap();
  if (!std::filesystem::is_directory(Scratch() / "dir") ||
      !std::filesystem::is_fifo(Scratch() / "fifo"))
    __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  CheckThePreflight(std::string_view(reinterpret_cast<const char*>(data), size));
  std::vector<std::string> errors;
  const auto scene = zephyr::ParseNff(std::string_view(reinterpret_cast<const char*>(data), size),
                                      "fuzz.nff", errors);
  if (!scene) {
    if (errors.empty()) __builtin_trap();  // a failed parse must say why
    return 0;
  }
  // A scene that parsed must be traceable (in double and float: a scene float cannot hold
  // is a UserError) and plannable for the SIMD pass (or a UserError saying why not); the
  // BVH (--accel bvh) must give the exhaustive tracer's pixels and primary hits bit for bit.
  if (scene->objects.size() <= 64) {
    for (const auto precision : {zephyr::Precision::kDouble, zephyr::Precision::kFloat}) {
      zephyr::TraceOptions options;
      options.precision = precision;
      try {
        const auto tracer = zephyr::Tracer::Create(*scene, options);
        options.accel = zephyr::Accel::kBvh;
        const auto bvh = zephyr::Tracer::Create(*scene, options);
        zephyr::TraceStats stats;
        const zephyr::Camera& c = scene->camera;
        for (int y : {0, c.height / 2, c.height - 1}) {
          for (int x : {0, c.width / 2, c.width - 1}) {
            zephyr::PrimaryHit a, b;
            const zephyr::Vec3 ca = tracer->TracePixel(x, y, stats, &a);
            const zephyr::Vec3 cb = bvh->TracePixel(x, y, stats, &b);
            if (a.object != b.object || std::memcmp(&a.t, &b.t, sizeof a.t) != 0 ||
                std::memcmp(&ca, &cb, sizeof ca) != 0)
              __builtin_trap();  // the hierarchy changed a result
          }
        }
      } catch (const zephyr::UserError&) {
        if (precision == zephyr::Precision::kDouble)
          __builtin_trap();  // the reader held it to double
      }
    }
    try {
      (void)zephyr::simd::PlanPrimaryPass(*scene, {});
    } catch (const zephyr::UserError&) {
    }
  }
  (void)zephyr::WriteNff(*scene);
  return 0;
}
