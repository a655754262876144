// hosts/cmd/accuracy.cpp — `zephyr accuracy SCENE`: a method's primary hits against an exact
// reference (SPEC §4). For every pixel (or a stated random sample) the first hit is
// recomputed with 128-bit binary floats (fixed/reference.h RefReal) along the same double
// eye ray: spheres, ellipsoids and cones (ray through T⁻¹) and polygons. Also the PSNR of the
// final image against the sequential method in double.
//
//   zephyr accuracy SCENE [--frac-bits N …]              the SIMD primary pass (default)
//   zephyr accuracy SCENE --method seq --precision float  the sequential tracer's first hits
//                                                         in float32 (or double: its PSNR
//                                                         against itself is inf)
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <random>

#include "fixed/check.h"
#include "fixed/reference.h"
#include "hosts/cmd/command.h"
#include "hosts/trace/image.h"
#include "hosts/scene/nff.h"
#include "hosts/methods/render.h"
#include "hosts/simd/pass.h"

namespace zephyr::simd {
namespace {

using Real = fixed::reference::RefReal;

struct RVec {
  Real x, y, z;
  Real operator[](int i) const { return i == 0 ? x : i == 1 ? y : z; }
};
RVec Make(const Vec3& v) { return {Real(v.x), Real(v.y), Real(v.z)}; }
RVec Minus(const RVec& a, const RVec& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Real Dot(const RVec& a, const RVec& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// The nearest sphere root beyond tMin along o + t·d (d not necessarily unit), exactly.
std::optional<Real> ExactSphere(const RVec& c, double radius, const RVec& o, const RVec& d, double tMin) {
  const RVec f = Minus(c, o);
  const Real dd = Dot(d, d);
  const Real tca = Dot(f, d) / dd;
  const RVec v = {f.x - tca * d.x, f.y - tca * d.y, f.z - tca * d.z};
  const Real disc = (Real(radius) * radius - Dot(v, v)) / dd;
  if (disc < 0) return std::nullopt;
  const Real root = sqrt(disc);
  if (tca - root > tMin) return tca - root;
  if (tca + root > tMin) return tca + root;
  return std::nullopt;
}

// The ray mapped by T⁻¹ (the inverse as the scene computes it, in double; then exact).
void ToObject(const Primitive& p, RVec& o, RVec& d) {
  if (!p.transform) return;
  const Affine inv = p.transform->Inverse();
  auto row = [&](int r, const RVec& v, bool point) {
    return Real(inv.m[r][0]) * v.x + Real(inv.m[r][1]) * v.y + Real(inv.m[r][2]) * v.z +
           (point ? Real(inv.m[r][3]) : Real(0));
  };
  o = {row(0, o, true), row(1, o, true), row(2, o, true)};
  d = {row(0, d, false), row(1, d, false), row(2, d, false)};
}

// A polygon exactly: its plane (Newell's normal) and the even-odd test in the projection
// that drops the normal's largest axis, all in 128-bit arithmetic.
std::optional<Real> ExactPolygon(const Polygon& poly, const RVec& o, const RVec& d, double tMin) {
  const size_t n = poly.vertices.size();
  std::vector<RVec> v;
  for (const Vec3& p : poly.vertices) v.push_back(Make(p));
  RVec nn{0, 0, 0};
  for (size_t i = 0; i < n; ++i) {
    const RVec &a = v[i], &b = v[(i + 1) % n];
    nn = {nn.x + (a.y - b.y) * (a.z + b.z), nn.y + (a.z - b.z) * (a.x + b.x), nn.z + (a.x - b.x) * (a.y + b.y)};
  }
  const Real nd = Dot(nn, d);
  if (nd == 0) return std::nullopt;
  const Real t = Dot(nn, Minus(v[0], o)) / nd;
  if (!(t > tMin)) return std::nullopt;
  const RVec hit = {o.x + t * d.x, o.y + t * d.y, o.z + t * d.z};
  const Real ax = abs(nn.x), ay = abs(nn.y), az = abs(nn.z);
  const int drop = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
  std::vector<Real> uv;
  for (const RVec& p : v) uv.push_back(p[(drop + 1) % 3]), uv.push_back(p[(drop + 2) % 3]);
  if (!InsidePolygon2D(uv, hit[(drop + 1) % 3], hit[(drop + 2) % 3])) return std::nullopt;
  return t;
}

// An open truncated cone (NFF `c`, as hosts/trace/intersect.h IntersectCone) exactly: the
// nearest root beyond tMin whose height lies in [0, h] on the nappe of non-negative radius.
std::optional<Real> ExactCone(const Cone& cone, const RVec& o, const RVec& d, double tMin) {
  const RVec base = Make(cone.base), axisFull = Minus(Make(cone.apex), base);
  const Real h = sqrt(Dot(axisFull, axisFull));
  const RVec a = {axisFull.x / h, axisFull.y / h, axisFull.z / h};
  const Real r0 = Real(cone.baseRadius), slope = (Real(cone.apexRadius) - r0) / h;
  const RVec w = Minus(o, base);
  const Real da = Dot(d, a), wa = Dot(w, a), rw = r0 + slope * wa;
  const Real qa = Dot(d, d) - da * da - slope * slope * da * da;
  const Real qb = Dot(w, d) - wa * da - slope * rw * da;  // half of b
  const Real qc = Dot(w, w) - wa * wa - rw * rw;
  Real t0, t1;
  if (qa == 0) {
    if (qb == 0) return std::nullopt;
    t0 = t1 = -qc / (2 * qb);
  } else {
    const Real disc = qb * qb - qa * qc;
    if (disc < 0) return std::nullopt;
    const Real root = sqrt(disc);
    const Real q = qb < 0 ? Real(root - qb) : Real(-(qb + root));
    t0 = q / qa;
    t1 = q != 0 ? qc / q : t0;
  }
  if (t1 < t0) std::swap(t0, t1);
  for (const Real& t : {t0, t1}) {
    if (!(t > tMin)) continue;
    const Real s = wa + t * da;
    if (s < 0 || s > h || r0 + slope * s < 0) continue;
    return t;
  }
  return std::nullopt;
}

// The exact first hit of one eye ray: the object (-1: none) and its t.
std::pair<int, Real> ExactFirstHit(const Scene& s, const PrimaryRay& ray, double tMin) {
  int best = -1;
  Real tBest = 0;
  for (size_t i = 0; i < s.objects.size(); ++i) {
    std::optional<Real> t;
    const Primitive& p = s.objects[i];
    RVec o = Make(ray.origin), d = Make(ray.direction);
    ToObject(p, o, d);
    if (const Sphere* sp = std::get_if<Sphere>(&p.shape)) {
      t = ExactSphere(Make(sp->center), sp->radius, o, d, tMin);
    } else if (const Polygon* poly = std::get_if<Polygon>(&p.shape)) {
      t = ExactPolygon(*poly, o, d, tMin);
    } else {
      t = ExactCone(std::get<Cone>(p.shape), o, d, tMin);
    }
    if (t && (best < 0 || *t < tBest)) best = int(i), tBest = *t;
  }
  return {best, tBest};
}

CommandRegistration reg("accuracy", [](CLI::App& program) {
  auto* cmd = program.add_subcommand(
      "accuracy", "Compare the SIMD primary pass (or the sequential tracer) with an exact (128-bit) reference");
  auto scene = std::make_shared<std::string>();
  auto sample = std::make_shared<int64_t>(0);
  auto o = std::make_shared<RenderOptions>();
  auto json = std::make_shared<bool>(false);
  auto method = std::make_shared<std::string>("simd");
  auto precision = std::make_shared<std::string>();
  cmd->add_option("scene", *scene, "NFF scene file")->required();
  cmd->add_option("--method", *method, "simd (default: the SIMD primary pass) or seq (the sequential tracer)");
  cmd->add_option("--precision", *precision, "--method seq: float or double (default double)");
  cmd->add_option("--sample", *sample, "Random sample of this many pixels (default: every pixel)");
  cmd->add_option("--frac-bits", o->extra["frac-bits"], "Fraction bits of lengths, t and directions");
  cmd->add_option("--dir-frac-bits", o->extra["dir-frac-bits"], "Fraction bits of the directions only");
  cmd->add_option("--int-bits", o->extra["int-bits"], "Integer bits of distances");
  cmd->add_option("--uncertain", o->extra["uncertain"], "recompute (default), keep or fail");
  cmd->add_flag("--json", *json, "Machine-readable output");
  cmd->callback([scene, sample, o, json, method, precision] {
    if (*method != "simd" && *method != "seq")
      throw UserError("--method: expected simd or seq, got '" + *method + "'");
    const bool simd = *method == "simd";
    if (simd && !precision->empty())
      throw UserError("--precision applies to --method seq (the SIMD pass is fixed point)");
    if (!simd)
      for (const char* flag : {"frac-bits", "dir-frac-bits", "int-bits", "uncertain"})
        if (!o->extra[flag].empty())
          throw UserError(std::string("--") + flag + " applies to --method simd only");
    TraceOptions seqOptions;
    seqOptions.precision = ParsePrecision(precision->empty() ? "double" : *precision);
    const Scene s = ReadNffFile(*scene);
    const Camera& c = s.camera;
    // The primary hits under test: the SIMD pass's matrix, or the sequential tracer's.
    PrimaryPass pass;
    std::unique_ptr<Tracer> seqTracer;
    if (simd) {
      pass = RunPrimaryPass(s, SimdOptionsFrom(*o));
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
    int64_t differ = 0, compared = 0;
    double maxErr = 0, sumErr = 0;
    TraceStats seqStats;
    for (int64_t pe : which) {
      const PrimaryRay ray = rays.At(int(pe % c.width), int(pe / c.width));
      const auto [best, tBest] = ExactFirstHit(s, ray, tMin);
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
    if (simd)
      ShadeRegion(*tracer, pass.matrix, 0, 0, c.width, c.height, image.pixels, stats);
    else
      RenderRegion(*seqTracer, 0, 0, c.width, c.height, image.pixels, stats);
    RenderRegion(*tracer, 0, 0, c.width, c.height, seqImage.pixels, stats);
    const double psnr = Psnr(image, seqImage);
    const std::string what = simd ? "the SIMD pass" : std::string("seq ") + PrecisionName(seqOptions.precision);
    nlohmann::json j = {{"scene", *scene}, {"method", *method}, {"pixels", which.size()},
                        {"sampled", which.size() < size_t(pixels)},
                        {"firstObjectDiffers", differ},
                        {"firstObjectDiffersPercent", 100.0 * differ / which.size()},
                        {"tMaxError", maxErr}, {"tMeanError", compared ? sumErr / compared : 0.0},
                        {"psnrDb", std::isfinite(psnr) ? nlohmann::json(psnr) : nlohmann::json("inf")}};
    if (simd) {
      j["tErrorBound"] = pass.plan.tErrorBound;
      j["uncertain"] = pass.Json()["uncertain"];
    } else {
      j["precision"] = PrecisionName(seqOptions.precision);
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
                (long long)pass.overflowPixels, (long long)pass.grazingPixels,
                (long long)pass.tiePixels, (long long)pass.recomputedPixels);
  });
});

}  // namespace
}  // namespace zephyr::simd
