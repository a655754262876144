// hosts/cmd/accuracy.cpp — `zephyr accuracy SCENE`: a method's primary hits against an exact
// reference (docs/simd.md, "Accuracy"). For every pixel (or a stated random sample) the first hit is
// recomputed by the exact reference (hosts/trace/exact.h, 128-bit floats) along the same
// double eye ray: spheres, ellipsoids and cones (ray through T⁻¹) and polygons. Also the PSNR of the
// final image against the sequential method in double.
//
//   zephyr accuracy SCENE [--frac-bits N …]              the SIMD primary pass (default)
//   zephyr accuracy SCENE --number float [--float-format e8m16]   ... in bit-serial float
//   zephyr accuracy SCENE --method seq --precision float  the sequential tracer's first hits
//                                                         in float32 (or double: its PSNR
//                                                         against itself is inf)
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/cmd/flags.h"
#include "hosts/methods/memory_budget.h"
#include "hosts/methods/report.h"
#include "hosts/cmd/simd_flags.h"
#include "hosts/trace/exact.h"
#include "hosts/trace/image.h"
#include "hosts/scene/nff.h"
#include "hosts/simd/pass.h"

namespace zephyr::simd {
namespace {

using Real = exact::Real;

CommandRegistration reg("accuracy", [](CLI::App& program) {
  auto* cmd = program.add_subcommand(
      "accuracy", "Compare the SIMD primary pass (or the sequential tracer) with an exact (128-bit) reference");
  auto scene = std::make_shared<std::string>();
  auto sample = std::make_shared<int64_t>(0);
  auto flags = std::make_shared<SimdFlags>();
  auto json = std::make_shared<bool>(false);
  auto method = std::make_shared<std::string>("simd");
  auto precision = std::make_shared<std::string>();
  cmd->add_option("scene", *scene, "NFF scene file")->required();
  cmd->add_option("--method", *method, "simd (default: the SIMD primary pass) or seq (the sequential tracer)");
  cmd->add_option("--precision", *precision, "--method seq: float or double (default double)");
  AddInteger(*cmd, "--sample", *sample, int64_t(0), int64_t(kMaxResolution) * kMaxResolution,
             "Random sample of this many pixels (0, the default: every pixel)");
  flags->AddTo(*cmd, "--method simd: ");
  cmd->add_flag("--json", *json, "Machine-readable output");
  cmd->callback([scene, sample, flags, json, method, precision] {
    if (*method != "simd" && *method != "seq")
      throw UserError("--method: expected simd or seq, got '" + *method + "'");
    const bool simd = *method == "simd";
    if (simd && !precision->empty())
      throw UserError("--precision applies to --method seq (the SIMD pass's numbers are --number)");
    if (!simd && !flags->Given().empty())
      throw UserError(flags->Given().front() + " applies to --method simd only");
    TraceOptions seqOptions;
    seqOptions.precision = ParsePrecision(precision->empty() ? "double" : *precision);
    const Scene s = ReadNffFile(*scene);
    const Camera& c = s.camera;
    // The pass's matrix and the exact reference per pixel: 110 bytes a pixel measured at
    // 1024x1024 (docs/errors.md, "Memory"), with a margin.
    CheckMemoryFits("accuracy at " + std::to_string(c.width) + "x" + std::to_string(c.height),
                    {.perPixel = 140, .pixels = uint64_t(c.width) * uint64_t(c.height)});
    // The primary hits under test: the SIMD pass's matrix, or the sequential tracer's.
    PrimaryPass pass;
    std::unique_ptr<Tracer> seqTracer;
    if (simd) {
      pass = RunPrimaryPass(s, flags->Options());
    } else {
      seqTracer = Tracer::Create(s, seqOptions);
    }
    const int64_t pixels = int64_t(c.width) * c.height;
    std::vector<int64_t> which;
    if (*sample <= 0 || *sample >= pixels) {
      for (int64_t i = 0; i < pixels; ++i) which.push_back(i);
    } else {
      std::mt19937_64 rng(1);
      std::uniform_int_distribution<int64_t> pick(0, pixels - 1);
      for (int64_t k = 0; k < *sample; ++k) which.push_back(pick(rng));
    }
    const PrimaryRays rays(c);
    const double tMin = std::max(c.hither, 0.0);
    const std::vector<int> planes = exact::CoplanarPolygons(s);
    int64_t differ = 0, compared = 0;
    double maxErr = 0, sumErr = 0;
    TraceStats seqStats;
    for (int64_t pe : which) {
      const PrimaryRay ray = rays.At(int(pe % c.width), int(pe / c.width));
      const auto [best, tBest] = exact::FirstHit(s, ray, tMin, planes);
      const PrimaryHit h = simd ? pass.matrix.hits[pe] : seqTracer->FirstHit(ray, seqStats);
      if (h.object != best) {
        ++differ;
        continue;
      }
      if (best < 0) continue;
      const double err = std::abs(double(Real(h.t) - tBest));
      maxErr = std::max(maxErr, err);
      sumErr += err;
      ++compared;
    }
    // PSNR of the final image (SIMD primary pass + host shading, or the sequential tracer in
    // its precision) against the sequential method in double, over every pixel.
    const auto tracer = Tracer::Create(s, TraceOptions{});
    TraceStats stats;
    Image image(c.width, c.height), seqImage(c.width, c.height);
    double seqSeconds = 0;  // the sequential tracer's render of the image (host seconds)
    if (simd) {
      ShadeRegion(*tracer, pass.matrix, 0, 0, c.width, c.height, image.pixels, stats);
    } else {
      const auto start = std::chrono::steady_clock::now();
      RenderRegion(*seqTracer, 0, 0, c.width, c.height, image.pixels, stats);
      seqSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    RenderRegion(*tracer, 0, 0, c.width, c.height, seqImage.pixels, stats);
    const double psnr = Psnr(image, seqImage);
    const std::string what = simd ? (pass.plan.number == NumberSystem::kFloat
                                          ? "the SIMD pass in float " + pass.plan.floatFormat.Name()
                                          : "the SIMD pass")
                                    : std::string("seq ") + PrecisionName(seqOptions.precision);
    nlohmann::json j = {{"scene", *scene}, {"method", *method}, {"pixels", which.size()},
                        {"sampled", which.size() < size_t(pixels)},
                        {"firstObjectDiffers", differ},
                        {"firstObjectDiffersPercent", 100.0 * differ / which.size()},
                        {"tMaxError", maxErr}, {"tMeanError", compared ? sumErr / compared : 0.0},
                        {"psnrDb", std::isfinite(psnr) ? nlohmann::json(psnr) : nlohmann::json("inf")}};
    if (simd) {
      // The pass's cost, for speed-against-accuracy charts: modelled cycles of the whole
      // primary pass (every array pass and layer) and the emulator's wall time.
      j["number"] = NumberSystemName(pass.plan.number);
      if (pass.plan.number == NumberSystem::kFloat) j["floatFormat"] = pass.plan.floatFormat.Name();
      j["fracBits"] = pass.plan.fracBits;
      const nlohmann::json section = PrimaryPassJson(pass);  // as render --report writes it
      j["cycles"] = pass.array.cycles.TotalCycles();
      j["hostSeconds"] = pass.array.hostSeconds;
      j["tErrorBound"] = pass.plan.tErrorBound;
      j["uncertain"] = section["uncertain"];
      if (pass.refine) j["refine"] = section["refine"];
    } else {
      j["precision"] = PrecisionName(seqOptions.precision);
      j["hostSeconds"] = seqSeconds;  // one render of the image in that precision (shading included)
    }
    if (*json) {
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    std::printf("%s: %s, %zu pixel(s)%s; reference: 128-bit spheres, ellipsoids, polygons and cones\n",
                scene->c_str(), what.c_str(), which.size(),
                j["sampled"].get<bool>() ? " (random sample, seed 1)" : " (every pixel)");
    std::printf("first object differs: %lld (%.4f %%)\n", (long long)differ, 100.0 * differ / which.size());
    std::printf("t error where the object agrees: max %.3g, mean %.3g", maxErr, compared ? sumErr / compared : 0.0);
    if (simd) std::printf(" (bound for certain pixels %.3g)", pass.plan.tErrorBound);
    std::printf("\nPSNR of the final image against the sequential method (double): %.2f dB%s\n", psnr,
                std::isfinite(psnr) ? "" : " (identical: seq double is the reference itself)");
    if (!simd) return;
    std::printf("uncertain: %lld overflow, %lld grazing, %lld near tie, %lld recomputed\n",
                (long long)pass.uncertain.overflow, (long long)pass.uncertain.grazing,
                (long long)pass.uncertain.nearTie, (long long)pass.recomputedPixels);
  });
});

}  // namespace
}  // namespace zephyr::simd
