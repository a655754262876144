// The refine pass's t (docs/simd.md, "Refine pass"): on adversarial 160x160 views (nearly
// touching spheres, a fan of grazing rays, radii 0.01–50), every pixel the refine pass
// certifies has a t within the refine plan's bound of its object, and within the first plan's,
// against the exact (128-bit) reference along the eye ray — and along the direction the matrix
// holds for it (the pair a dump or a heterogeneous child reads), which is the refine pass's own.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "hosts/scene/nff.h"
#include "hosts/simd/direction.h"
#include "hosts/simd/pass.h"
#include "hosts/trace/exact.h"

namespace zephyr::simd {
namespace {

constexpr int kSize = 160;

Scene Spheres(const Vec3& from, const Vec3& at, double angle, const std::vector<Sphere>& spheres) {
  Scene s;
  s.source = "refine t test";
  s.camera = Camera{from, at, {0, 1, 0}, angle, 0.01, kSize, kSize};
  s.lights = {Light{{5, 5, 5}, {1, 1, 1}}};
  s.materials = {Material{}};
  for (const Sphere& sp : spheres) {
    Primitive p;
    p.shape = sp;
    s.objects.push_back(p);
  }
  return s;
}

// Pairs of spheres touching (gap 0, 1e-9 and 1e-6 of the radii's sum) side by side, where the
// rays through the contact graze both: radii from 0.01 to 50.
Scene TouchingSpheres() {
  std::vector<Sphere> s;
  const double radii[][2] = {{1, 1}, {0.3, 0.01}, {50, 2}, {0.05, 0.05}, {4, 0.5}};
  const double gaps[] = {0, 1e-9, 1e-6, 0, 1e-9};
  const Vec3 centres[] = {
      {-1, 0, -10}, {1.5, 1.5, -9}, {-60, -20, -150}, {-1.2, -1.8, -8}, {1.2, -1.2, -14}};
  for (int k = 0; k < 5; ++k) {
    const Vec3 n = Normalize(Vec3{1, 0.2 * k - 0.4, 0.1});
    s.push_back({centres[k], radii[k][0]});
    s.push_back({centres[k] + n * ((radii[k][0] + radii[k][1]) * (1 + gaps[k])), radii[k][1]});
  }
  return Spheres({0, 0, 0}, {0, 0, -10}, 40, s);
}

// A 3° view centred on the silhouette of a radius-50 sphere 150 away, a radius-0.01 sphere
// grazed by the same rays and a radius-2 sphere behind both.
Scene GrazingFan() {
  const Vec3 c{0, 0, -150};
  const double r = 50;
  const double tangent = std::sqrt(150.0 * 150.0 - r * r);
  const Vec3 edge = Normalize(
      Vec3{r / 150 * tangent, 0, -tangent / 150 * tangent});  // direction to the silhouette
  return Spheres(
      {0, 0, 0}, edge * 100.0, 3,
      {{c, r}, {edge * 120.0 + Vec3{0.01, 0.2, 0}, 0.01}, {edge * 160.0 + Vec3{1, 0.5, 0}, 2}});
}

// Nearly touching pairs (gaps 0 to 1e-4 of the radii's sum, or cutting by 1e-3) with radii
// log-uniform in [0.01, 50], from a fixed seed.
Scene MixedRadii() {
  std::mt19937_64 g(4);
  std::uniform_real_distribution<double> u(0, 1);
  auto logUniform = [&](double a, double b) { return a * std::pow(b / a, u(g)); };
  std::vector<Sphere> s;
  const double dist = 40;
  for (int k = 0; k < 6; ++k) {
    const double r1 = logUniform(0.01, 50), r2 = logUniform(0.01, 50);
    const Vec3 c{(u(g) - 0.5) * dist * 0.3, (u(g) - 0.5) * dist * 0.3, -dist * (0.5 + u(g))};
    const Vec3 n = Normalize(Vec3{u(g) - 0.5, u(g) - 0.5, (u(g) - 0.5) * 0.6});
    const double gaps[] = {0, 1e-9, 1e-6, 1e-4, -1e-3};
    s.push_back({c, r1});
    s.push_back({c + n * ((r1 + r2) * (1 + gaps[k % 5])), r2});
  }
  return Spheres({1, -1, 0}, {0, 0, -dist}, 45, s);
}

// Over the pixels the refine pass certified whose object is the exact one.
struct RefinedT {
  int pixels = 0;
  // |t − exact| of the refine pass's matrix above the first pass's (`keep`), each along the
  // direction its own matrix holds (what a dump names), and the largest ratio of the two.
  int worseThanFirst = 0;
  double worstRatio = 0;
  // The largest |t − exact| / the refine plan's tError of the object, along the eye ray and
  // along the matrix's direction; and the larger of the two / the first plan's tError.
  double eyeShare = 0, matrixShare = 0, firstShare = 0;
};

RefinedT Measure(const Scene& scene, int fracBits) {
  SimdOptions o;
  o.formats.fracBits = fracBits;
  o.uncertain = UncertainPolicy::kKeep;
  const PrimaryPass first = RunPrimaryPass(scene, o);
  o.uncertain = UncertainPolicy::kRefine;
  const PrimaryPass refined = RunPrimaryPass(scene, o);
  const PrimaryPlan plan =
      PlanRefinePass(scene, o, refined.plan, refined.RefinedPixels(), kRefineExtraBits);
  const PrimaryRays rays(scene.camera);
  const double tMin = std::max(scene.camera.hither, 0.0);
  const std::vector<int> planes = exact::CoplanarPolygons(scene);
  RefinedT r;
  for (size_t i = 0; i < refined.matrix.hits.size(); ++i) {
    if (first.matrix.flags[i] == 0 || (refined.matrix.flags[i] & ~kRefined) != 0) continue;
    const PrimaryHit& h = refined.matrix.hits[i];
    PrimaryRay ray = rays.At(int(i % kSize), int(i / kSize));
    const exact::Hit eye = exact::FirstHit(scene, ray, tMin, planes);
    if (h.object < 0 || eye.object != h.object)
      continue;  // the objects: SimdRefine's soundness tests
    ray.direction = h.direction;
    const exact::Hit along = exact::FirstHit(scene, ray, tMin, planes);
    ray.direction = first.matrix.hits[i].direction;
    const exact::Hit alongFirst = exact::FirstHit(scene, ray, tMin, planes);
    const double bound = plan.objects[h.object].bounds.tError;
    const double firstBound = first.plan.objects[h.object].bounds.tError;
    const double eEye = std::abs(double(exact::Real(h.t) - eye.t));
    const double eMatrix =
        along.object == h.object ? std::abs(double(exact::Real(h.t) - along.t)) : kInf;
    ++r.pixels;
    r.eyeShare = std::max(r.eyeShare, eEye / bound);
    r.matrixShare = std::max(r.matrixShare, eMatrix / bound);
    r.firstShare = std::max(r.firstShare, std::max(eEye, eMatrix) / firstBound);
    if (first.matrix.hits[i].object == h.object && alongFirst.object == h.object) {
      const double eFirst = std::abs(double(exact::Real(first.matrix.hits[i].t) - alongFirst.t));
      if (eMatrix > eFirst)
        ++r.worseThanFirst,
            r.worstRatio = std::max(r.worstRatio, eMatrix / std::max(eFirst, 1e-300));
    }
  }
  return r;
}

TEST(SimdRefine, RefinedTIsWithinTheRefineBound) {
  const std::pair<const char*, Scene> scenes[] = {
      {"touching", TouchingSpheres()}, {"grazing", GrazingFan()}, {"mixed radii", MixedRadii()}};
  for (const auto& [name, scene] : scenes)
    for (int bits : {10, -1}) {
      const RefinedT r = Measure(scene, bits);
      const std::string what = fmt::format("{} at {} fraction bits", name, bits);
      std::printf(
          "%s: %d refined certain, %d worse than the first pass (max %.3gx); max error / refine "
          "bound: "
          "eye ray %.3g, matrix direction %.3g; / first bound %.3g\n",
          what.c_str(), r.pixels, r.worseThanFirst, r.worstRatio, r.eyeShare, r.matrixShare,
          r.firstShare);
      RecordProperty(fmt::format("{} {} bits", name, bits),
                     fmt::format("refined {} worse {} eye/bound {:.3g} matrix/bound {:.3g}",
                                 r.pixels, r.worseThanFirst, r.eyeShare, r.matrixShare));
      EXPECT_GT(r.pixels, 150) << what;
      EXPECT_LE(r.eyeShare, 1) << what;
      EXPECT_LE(r.matrixShare, 1) << what;  // 11-26x with the first pass's direction beside the t
      EXPECT_LE(r.firstShare, 1) << what;
      // A first pass's t may be closer by chance (within its own bound); before the refined
      // pixels took the refine pass's direction, 55-76 % of them were.
      EXPECT_LE(r.worseThanFirst, r.pixels / 100) << what;
    }
}

}  // namespace
}  // namespace zephyr::simd
