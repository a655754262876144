// hosts/simd_accuracy.cpp — `zephyr accuracy SCENE`: the SIMD primary pass against an exact
// reference (SPEC §4). For every pixel (or a stated random sample) the first hit is
// recomputed with 128-bit binary floats (fixed/reference.h RefReal) along the same double
// eye ray: spheres exactly by Hearn–Baker; other primitives in double (stated in the output).
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <random>

#include "fixed/check.h"
#include "fixed/reference.h"
#include "hosts/command.h"
#include "hosts/nff.h"
#include "hosts/render.h"
#include "hosts/simd.h"

namespace zephyr::simd {
namespace {

using Real = fixed::reference::RefReal;

// The nearest sphere root beyond tMin along o + t·d, exactly (d is the double unit vector).
std::optional<Real> ExactSphere(const Sphere& s, const Vec3& o, const Vec3& d, double tMin) {
  const Real fx = Real(s.center.x) - o.x, fy = Real(s.center.y) - o.y, fz = Real(s.center.z) - o.z;
  const Real dx = d.x, dy = d.y, dz = d.z;
  const Real dd = dx * dx + dy * dy + dz * dz;
  const Real tca = (fx * dx + fy * dy + fz * dz) / dd;
  const Real vx = fx - tca * dx, vy = fy - tca * dy, vz = fz - tca * dz;
  const Real disc = (Real(s.radius) * s.radius - (vx * vx + vy * vy + vz * vz)) / dd;
  if (disc < 0) return std::nullopt;
  const Real root = sqrt(disc);
  if (tca - root > tMin) return tca - root;
  if (tca + root > tMin) return tca + root;
  return std::nullopt;
}

CommandRegistration reg("accuracy", [](CLI::App& program) {
  auto* cmd = program.add_subcommand("accuracy", "Compare the SIMD primary pass with an exact (128-bit) reference");
  auto scene = std::make_shared<std::string>();
  auto sample = std::make_shared<int64_t>(0);
  auto o = std::make_shared<RenderOptions>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("scene", *scene, "NFF scene file")->required();
  cmd->add_option("--sample", *sample, "Random sample of this many pixels (default: every pixel)");
  cmd->add_option("--frac-bits", o->extra["frac-bits"], "Fraction bits of lengths, t and directions");
  cmd->add_option("--dir-frac-bits", o->extra["dir-frac-bits"], "Fraction bits of the directions only");
  cmd->add_option("--int-bits", o->extra["int-bits"], "Integer bits of distances");
  cmd->add_option("--uncertain", o->extra["uncertain"], "recompute (default), keep or fail");
  cmd->add_flag("--json", *json, "Machine-readable output");
  cmd->callback([scene, sample, o, json] {
    const Scene s = ReadNffFile(*scene);
    const PrimaryPass pass = RunPrimaryPass(s, SimdOptionsFrom(*o));
    const Camera& c = s.camera;
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
    int64_t differ = 0, compared = 0, nonSphere = 0;
    double maxErr = 0, sumErr = 0;
    for (int64_t pe : which) {
      const PrimaryRay ray = rays.At(int(pe % c.width), int(pe / c.width));
      int best = -1;
      Real tBest = 0;
      for (size_t i = 0; i < s.objects.size(); ++i) {
        std::optional<Real> t;
        const Primitive& p = s.objects[i];
        if (p.Kind() == ShapeKind::kSphere && !p.transform) {
          t = ExactSphere(std::get<Sphere>(p.shape), ray.origin, ray.direction, tMin);
        } else {
          if (auto td = IntersectObject(s, int(i), ray.origin, ray.direction, tMin)) t = Real(*td);
          ++nonSphere;
        }
        if (t && (best < 0 || *t < tBest)) best = int(i), tBest = *t;
      }
      const PrimaryHit& h = pass.matrix.hits[pe];
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
    nlohmann::json j = {{"scene", *scene}, {"pixels", which.size()},
                        {"sampled", which.size() < size_t(pixels)},
                        {"firstObjectDiffers", differ},
                        {"firstObjectDiffersPercent", 100.0 * differ / which.size()},
                        {"tMaxError", maxErr}, {"tMeanError", compared ? sumErr / compared : 0.0},
                        {"tErrorBound", pass.plan.tErrorBound},
                        {"nonSphereTestsInDouble", nonSphere},
                        {"uncertain", pass.Json()["uncertain"]}};
    if (*json) {
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    std::printf("%s: %zu pixel(s)%s; reference: 128-bit Hearn-Baker for spheres%s\n", scene->c_str(),
                which.size(), j["sampled"].get<bool>() ? " (random sample, seed 1)" : " (every pixel)",
                nonSphere ? ", double for other primitives" : "");
    std::printf("first object differs: %lld (%.4f %%)\n", (long long)differ, 100.0 * differ / which.size());
    std::printf("t error where the object agrees: max %.3g, mean %.3g (bound for certain pixels %.3g)\n",
                maxErr, compared ? sumErr / compared : 0.0, pass.plan.tErrorBound);
    std::printf("uncertain: %lld overflow, %lld grazing, %lld near tie, %lld recomputed\n",
                (long long)pass.overflowPixels, (long long)pass.grazingPixels,
                (long long)pass.tiePixels, (long long)pass.recomputedPixels);
  });
});

}  // namespace
}  // namespace zephyr::simd
