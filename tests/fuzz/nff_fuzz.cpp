// libFuzzer target for the NFF reader, the host tracer and the SIMD planner: any input must
// give a scene or a list of errors, and a scene must trace and plan or raise a UserError
// (a clear message) — never a crash, an internal-check abort, a hang or a sanitizer report. Built by `make fuzz` with clang,
// -fsanitize=fuzzer,address,undefined; seeds come from tests/fuzz/corpus/.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fixed/check.h"
#include "hosts/scene/nff.h"
#include "hosts/simd/plan.h"
#include "hosts/trace/tracer.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<std::string> errors;
  const auto scene = zephyr::ParseNff(std::string_view(reinterpret_cast<const char*>(data), size),
                                      "fuzz.nff", errors);
  if (!scene) {
    if (errors.empty()) __builtin_trap();  // a failed parse must say why
    return 0;
  }
  // A scene that parsed must be traceable (in double and float: a scene float cannot hold
  // is a UserError) and plannable for the SIMD pass (or a UserError saying why not).
  if (scene->objects.size() <= 64) {
    for (const auto precision : {zephyr::Precision::kDouble, zephyr::Precision::kFloat}) {
      zephyr::TraceOptions options;
      options.precision = precision;
      try {
        const auto tracer = zephyr::Tracer::Create(*scene, options);
        zephyr::TraceStats stats;
        const zephyr::Camera& c = scene->camera;
        for (int y : {0, c.height / 2, c.height - 1}) {
          for (int x : {0, c.width / 2, c.width - 1}) tracer->TracePixel(x, y, stats);
        }
      } catch (const zephyr::UserError&) {
        if (precision == zephyr::Precision::kDouble) __builtin_trap();  // the reader held it to double
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
