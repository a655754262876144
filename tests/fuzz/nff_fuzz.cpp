// libFuzzer target for the NFF reader: any input must give a scene or a list of errors,
// never a crash, a hang or a sanitizer report. Built by `make fuzz` with clang,
// -fsanitize=fuzzer,address,undefined; seeds come from tests/fuzz/corpus/.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hosts/scene/nff.h"
#include "hosts/trace/tracer.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<std::string> errors;
  const auto scene = zephyr::ParseNff(std::string_view(reinterpret_cast<const char*>(data), size),
                                      "fuzz.nff", errors);
  if (!scene) {
    if (errors.empty()) __builtin_trap();  // a failed parse must say why
    return 0;
  }
  // A scene that parsed must be traceable: trace a few primary rays through it.
  if (scene->objects.size() <= 64) {
    const auto tracer = zephyr::Tracer::Create(*scene, {});
    zephyr::TraceStats stats;
    const zephyr::Camera& c = scene->camera;
    for (int y : {0, c.height / 2, c.height - 1}) {
      for (int x : {0, c.width / 2, c.width - 1}) tracer->TracePixel(x, y, stats);
    }
  }
  (void)zephyr::WriteNff(*scene);
  return 0;
}
