// hosts/methods/accuracy.h — a method's primary hits against an exact reference (docs/simd.md,
// "Accuracy"), the study behind `zephyr accuracy` (hosts/cmd/accuracy.cpp holds its flags and
// output). For every pixel (or a stated random sample) the first hit is recomputed by the exact
// reference (hosts/trace/exact.h, 128-bit floats) along the same double eye ray: spheres,
// ellipsoids and cones (ray through T⁻¹) and polygons. Also the PSNR of the final image
// against the sequential method in double.
//
//   const AccuracyResult r = MeasureAccuracy(scene, {.simd = true, .simdOptions = o});
//   r.firstObjectDiffers, r.tMaxError, r.psnrDb, AccuracyJson(r, "scene.nff")
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>

#include "hosts/scene/scene.h"
#include "hosts/simd/pass.h"
#include "hosts/trace/tracer.h"

namespace zephyr {

// What to measure.
struct AccuracyRequest {
  bool simd = true;                          // the SIMD primary pass; false: the sequential tracer
  simd::SimdOptions simdOptions;             // the pass's, with simd
  Precision precision = Precision::kDouble;  // the sequential tracer's scalar, without simd
  int64_t sample = 0;  // pixels in a random sample (seed 1); 0 or at least the image: every pixel
};

// What it measured. Lengths in scene units.
struct AccuracyResult {
  AccuracyRequest request;
  int64_t pixels = 0;                    // compared with the reference
  bool sampled = false;                  // a random sample, not every pixel
  int64_t firstObjectDiffers = 0;        // pixels whose first object is not the reference's
  double tMaxError = 0, tMeanError = 0;  // |t − t_exact| where the first object agrees and is hit
  double psnrDb = 0;                     // the final image against seq in double; inf: identical
  std::optional<simd::PrimaryPass> pass;  // with simd: the pass measured (plan, cycles, uncertain)
  double seqSeconds = 0;                  // without simd: one render of the image in that precision
  std::string What() const;  // "the SIMD pass", "the SIMD pass in float e8m16", "seq float"
};

// UserError as the SIMD pass (a scene that cannot be planned, --uncertain fail).
AccuracyResult MeasureAccuracy(const Scene& scene, const AccuracyRequest& request);

// `zephyr accuracy --json`'s object (docs/simd.md, "Accuracy"): the figures above and, with
// simd, the pass's cost (cycles, hostSeconds, number, floatFormat, fracBits, uncertain, refine).
nlohmann::json AccuracyJson(const AccuracyResult& result, const std::string& scenePath);

}  // namespace zephyr
