// hosts/cmd/accuracy.cpp — `zephyr accuracy SCENE`: the flags and the output of the accuracy
// study (hosts/methods/accuracy.h; docs/simd.md, "Accuracy").
//
//   zephyr accuracy SCENE [--frac-bits N …]              the SIMD primary pass (default)
//   zephyr accuracy SCENE --number float [--float-format e8m16]   ... in bit-serial float
//   zephyr accuracy SCENE --method seq --precision float  the sequential tracer's first hits
//                                                         in float32 (or double: its PSNR
//                                                         against itself is inf)
#include "hosts/methods/accuracy.h"

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/cmd/flags.h"
#include "hosts/cmd/simd_flags.h"
#include "hosts/methods/memory_budget.h"
#include "hosts/scene/nff.h"

namespace zephyr {
namespace {

CommandRegistration reg("accuracy", [](CLI::App& program) {
  auto* cmd = program.add_subcommand(
      "accuracy",
      "Compare the SIMD primary pass (or the sequential tracer) with an exact (128-bit) reference");
  auto scene = std::make_shared<std::string>();
  auto sample = std::make_shared<int64_t>(0);
  auto flags = std::make_shared<SimdFlags>();
  auto json = std::make_shared<bool>(false);
  auto method = std::make_shared<std::string>("simd");
  auto precision = std::make_shared<Precision>(Precision::kDouble);
  cmd->add_option("scene", *scene, "NFF scene file")->required();
  cmd->add_option("--method", *method,
                  "simd (default: the SIMD primary pass) or seq (the sequential tracer)");
  CLI::Option* precisionFlag =
      AddNamed(*cmd, "--precision", *precision, kPrecisionNames, "--method seq: float or double");
  AddInteger(*cmd, "--sample", *sample, int64_t(0), int64_t(kMaxResolution) * kMaxResolution,
             "Random sample of this many pixels (0, the default: every pixel)");
  flags->AddTo(*cmd, "--method simd: ");
  cmd->add_flag("--json", *json, "Machine-readable output");
  cmd->callback([scene, sample, flags, json, method, precision, precisionFlag] {
    if (*method != "simd" && *method != "seq")
      throw UserError("--method: expected simd or seq, got '" + *method + "'");
    const bool simd = *method == "simd";
    if (simd && precisionFlag->count() > 0)
      throw UserError("--precision applies to --method seq (the SIMD pass's numbers are --number)");
    if (!simd && !flags->Given().empty())
      throw UserError(flags->Given().front() + " applies to --method simd only");
    const Scene s = ReadNffFile(*scene);
    const Camera& c = s.camera;
    // The pass's matrix and the exact reference per pixel: 110 bytes a pixel measured at
    // 1024x1024 (docs/errors.md, "Memory"), with a margin.
    CheckMemoryFits("accuracy at " + std::to_string(c.width) + "x" + std::to_string(c.height),
                    {.perPixel = 140, .pixels = uint64_t(c.width) * uint64_t(c.height)});
    const AccuracyResult r =
        MeasureAccuracy(s, {.simd = simd,
                            .simdOptions = simd ? flags->Options() : simd::SimdOptions{},
                            .precision = *precision,
                            .sample = *sample});
    const nlohmann::json j = AccuracyJson(r, *scene);
    if (*json) {
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    std::printf(
        "%s: %s, %lld pixel(s)%s; reference: 128-bit spheres, ellipsoids, polygons and cones\n",
        scene->c_str(), r.What().c_str(), (long long)r.pixels,
        r.sampled ? " (random sample, seed 1)" : " (every pixel)");
    std::printf("first object differs: %lld (%.4f %%)\n", (long long)r.firstObjectDiffers,
                100.0 * double(r.firstObjectDiffers) / double(r.pixels));
    std::printf("t error where the object agrees: max %.3g, mean %.3g", r.tMaxError, r.tMeanError);
    if (r.pass) std::printf(" (bound for certain pixels %.3g)", r.pass->plan.tErrorBound);
    std::printf("\nPSNR of the final image against the sequential method (double): %.2f dB%s\n",
                r.psnrDb,
                std::isfinite(r.psnrDb) ? "" : " (identical: seq double is the reference itself)");
    if (!r.pass) return;
    std::printf("uncertain: %lld overflow, %lld grazing, %lld near tie, %lld recomputed\n",
                (long long)r.pass->uncertain.overflow, (long long)r.pass->uncertain.grazing,
                (long long)r.pass->uncertain.nearTie, (long long)r.pass->recomputedPixels);
  });
});

}  // namespace
}  // namespace zephyr
