// hosts/methods/accuracy.cpp — a method's primary hits against the exact reference
// (hosts/methods/accuracy.h).
#include "hosts/methods/accuracy.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <vector>

#include "hosts/methods/report.h"
#include "hosts/trace/exact.h"
#include "hosts/trace/image.h"

namespace zephyr {

using Real = exact::Real;

std::string AccuracyResult::What() const {
  if (!request.simd) return std::string("seq ") + kPrecisionNames.NameOf(request.precision);
  if (pass && pass->plan.number == simd::NumberSystem::kFloat)
    return "the SIMD pass in float " + pass->plan.floatFormat.Name();
  return "the SIMD pass";
}

AccuracyResult MeasureAccuracy(const Scene& s, const AccuracyRequest& request) {
  AccuracyResult r;
  r.request = request;
  const Camera& c = s.camera;
  TraceOptions seqOptions;
  seqOptions.precision = request.precision;
  // The primary hits under test: the SIMD pass's matrix, or the sequential tracer's.
  std::unique_ptr<Tracer> seqTracer;
  if (request.simd)
    r.pass = simd::RunPrimaryPass(s, request.simdOptions);
  else
    seqTracer = Tracer::Create(s, seqOptions);
  const int64_t pixels = int64_t(c.width) * c.height;
  std::vector<int64_t> which;
  if (request.sample <= 0 || request.sample >= pixels) {
    for (int64_t i = 0; i < pixels; ++i) which.push_back(i);
  } else {
    std::mt19937_64 rng(1);
    std::uniform_int_distribution<int64_t> pick(0, pixels - 1);
    for (int64_t k = 0; k < request.sample; ++k) which.push_back(pick(rng));
  }
  r.pixels = int64_t(which.size());
  r.sampled = which.size() < size_t(pixels);
  const PrimaryRays rays(c);
  const double tMin = std::max(c.hither, 0.0);
  const std::vector<int> planes = exact::CoplanarPolygons(s);
  int64_t compared = 0;
  double sumErr = 0;
  TraceStats seqStats;
  for (int64_t pe : which) {
    const PrimaryRay ray = rays.At(int(pe % c.width), int(pe / c.width));
    const auto [best, tBest] = exact::FirstHit(s, ray, tMin, planes);
    const PrimaryHit h = r.pass ? r.pass->matrix.hits[pe] : seqTracer->FirstHit(ray, seqStats);
    if (h.object != best) {
      ++r.firstObjectDiffers;
      continue;
    }
    if (best < 0) continue;
    const double err = std::abs(double(Real(h.t) - tBest));
    r.tMaxError = std::max(r.tMaxError, err);
    sumErr += err;
    ++compared;
  }
  r.tMeanError = compared ? sumErr / compared : 0.0;
  // PSNR of the final image (SIMD primary pass + host shading, or the sequential tracer in
  // its precision) against the sequential method in double, over every pixel.
  const auto tracer = Tracer::Create(s, TraceOptions{});
  TraceStats stats;
  Image image(c.width, c.height), seqImage(c.width, c.height);
  if (r.pass) {
    simd::ShadeRegion(*tracer, r.pass->matrix, 0, 0, c.width, c.height, image.pixels, stats);
  } else {
    const auto start = std::chrono::steady_clock::now();
    RenderRegion(*seqTracer, 0, 0, c.width, c.height, image.pixels, stats);
    r.seqSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  RenderRegion(*tracer, 0, 0, c.width, c.height, seqImage.pixels, stats);
  r.psnrDb = Psnr(image, seqImage);
  return r;
}

nlohmann::json AccuracyJson(const AccuracyResult& r, const std::string& scenePath) {
  nlohmann::json j = {
      {"scene", scenePath},
      {"method", r.request.simd ? "simd" : "seq"},
      {"pixels", r.pixels},
      {"sampled", r.sampled},
      {"firstObjectDiffers", r.firstObjectDiffers},
      {"firstObjectDiffersPercent", 100.0 * double(r.firstObjectDiffers) / double(r.pixels)},
      {"tMaxError", r.tMaxError},
      {"tMeanError", r.tMeanError},
      {"psnrDb", std::isfinite(r.psnrDb) ? nlohmann::json(r.psnrDb) : nlohmann::json("inf")}};
  if (r.pass) {
    // The pass's cost, for speed-against-accuracy charts: modelled cycles of the whole
    // primary pass (every array pass and layer) and the emulator's wall time.
    const simd::PrimaryPass& pass = *r.pass;
    j["number"] = simd::kNumberSystemNames.NameOf(pass.plan.number);
    if (pass.plan.number == simd::NumberSystem::kFloat)
      j["floatFormat"] = pass.plan.floatFormat.Name();
    j["fracBits"] = pass.plan.fracBits;
    const nlohmann::json section = PrimaryPassJson(pass);  // as render --report writes it
    j["cycles"] = pass.array.cycles.TotalCycles();
    j["hostSeconds"] = pass.array.hostSeconds;
    j["tErrorBound"] = pass.plan.tErrorBound;
    j["uncertain"] = section["uncertain"];
    if (pass.refine) j["refine"] = section["refine"];
  } else {
    j["precision"] = kPrecisionNames.NameOf(r.request.precision);
    j["hostSeconds"] =
        r.seqSeconds;  // one render of the image in that precision (shading included)
  }
  return j;
}

}  // namespace zephyr
