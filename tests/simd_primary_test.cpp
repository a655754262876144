// The SIMD/sequential method's primary pass against the sequential tracer (double).
#include <gtest/gtest.h>

#include <cmath>

#include "fixed/check.h"
#include "hosts/simd.h"
#include "tools/gen.h"

namespace zephyr::simd {
namespace {

// Every pixel's first object from the sequential tracer in double.
std::vector<PrimaryHit> SequentialHits(const Scene& scene) {
  TraceOptions o;
  o.depth = 1;
  const auto tracer = Tracer::Create(scene, o);
  TraceStats stats;
  std::vector<PrimaryHit> hits;
  for (int y = 0; y < scene.camera.height; ++y)
    for (int x = 0; x < scene.camera.width; ++x) hits.push_back(tracer->FirstHit(tracer->Rays().At(x, y), stats));
  return hits;
}

int ObjectMismatches(const PrimaryMatrix& m, const std::vector<PrimaryHit>& want) {
  int bad = 0;
  for (size_t i = 0; i < want.size(); ++i) bad += m.hits[i].object != want[i].object;
  return bad;
}

TEST(SimdPrimary, FirstObjectAgreesOnEveryPixelRandomSpheres) {
  const Scene scene = GenerateRandomSpheres({.count = 48, .seed = 3, .width = 64, .height = 64});
  const PrimaryPass pass = RunPrimaryPass(scene, {});
  EXPECT_EQ(ObjectMismatches(pass.matrix, SequentialHits(scene)), 0);
  EXPECT_EQ(pass.plan.layers, 1);
  EXPECT_GT(pass.cycles["totalCycles"].get<double>(), 0);
}

TEST(SimdPrimary, FirstObjectAgreesOnEveryPixelSphereflake) {
  const Scene scene = GenerateSphereflake(2, 64, 64);  // 91 spheres and a floor polygon
  const PrimaryPass pass = RunPrimaryPass(scene, {});
  const auto want = SequentialHits(scene);
  EXPECT_EQ(ObjectMismatches(pass.matrix, want), 0);
  // Where the hit is certain, t is within the stated bound of the double tracer's t.
  for (size_t i = 0; i < want.size(); ++i)
    if (pass.matrix.flags[i] == 0 && want[i].object >= 0) {
      ASSERT_NEAR(pass.matrix.hits[i].t, want[i].t, pass.plan.tErrorBound) << i;
    }
}

TEST(SimdPrimary, ColoursAgreeWithSequentialWhereTheHitIsTheSame) {
  const Scene scene = GenerateRandomSpheres({.count = 24, .seed = 5, .width = 48, .height = 48});
  const PrimaryPass pass = RunPrimaryPass(scene, {});
  TraceOptions o;
  const auto tracer = Tracer::Create(scene, o);
  std::vector<Vec3> simd;
  TraceStats stats;
  ShadeRegion(*tracer, pass.matrix, 0, 0, 48, 48, simd, stats);
  // Tolerance: a t error ε moves the hit point by ε; shading is smooth except where the
  // secondary rays cross a silhouette, so ≥ 99 % of pixels within 1e-3 and all within 1/8.
  int close = 0, same = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 48; ++x) {
      const size_t i = size_t(y) * 48 + x;
      PrimaryHit seqHit;
      const Vec3 want = tracer->TracePixel(x, y, stats, &seqHit);
      if (seqHit.object != pass.matrix.hits[i].object) continue;
      ++same;
      const Vec3 d = want - simd[i];
      const double err = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
      close += err <= 1e-3;
      EXPECT_LE(err, 0.125) << x << "," << y;
    }
  EXPECT_EQ(same, 48 * 48);
  EXPECT_GE(close, same * 99 / 100);
}

TEST(SimdPrimary, ShadeRegionIsBitIdenticalToTheFullImage) {
  const Scene scene = GenerateRandomSpheres({.count = 12, .seed = 2, .width = 40, .height = 32});
  const PrimaryPass pass = RunPrimaryPass(scene, {});
  const auto tracer = Tracer::Create(scene, TraceOptions{});
  std::vector<Vec3> full, part;
  TraceStats stats;
  ShadeRegion(*tracer, pass.matrix, 0, 0, 40, 32, full, stats);
  ShadeRegion(*tracer, pass.matrix, 8, 4, 16, 20, part, stats);
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 16; ++x) ASSERT_EQ(part[size_t(y) * 16 + x], full[size_t(y + 4) * 40 + x + 8]);
}

TEST(SimdPrimary, SceneThatCannotFitIsAClearError) {
  Scene scene = GenerateRandomSpheres({.count = 8, .seed = 1, .width = 4096, .height = 4096});
  try {
    PlanPrimaryPass(scene, {});
    FAIL() << "a 4096x4096 image (2048 layers) should not fit";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("does not fit"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2048 layers"), std::string::npos) << e.what();
  }
}

TEST(SimdPrimary, PlannerFollowsTheSceneAndTheOverrides) {
  Scene scene = GenerateRandomSpheres({.count = 8, .seed = 1, .width = 384, .height = 384});
  const PrimaryPlan base = PlanPrimaryPass(scene, {});
  EXPECT_EQ(base.layers, 18);  // 147,456 rays = 18 × 8192 (SPEC §3)
  EXPECT_EQ(base.dirFracBits, base.fracBits);
  // Smaller spheres need more fraction bits; a farther scene more integer bits.
  Scene small = scene, far = scene;
  for (Primitive& p : small.objects) std::get<Sphere>(p.shape).radius /= 16;
  for (Primitive& p : far.objects) std::get<Sphere>(p.shape).center = std::get<Sphere>(p.shape).center * 64.0;
  far.camera.from = far.camera.from * 64.0;
  EXPECT_EQ(PlanPrimaryPass(small, {}).fracBits, base.fracBits + 4);
  EXPECT_GE(PlanPrimaryPass(far, {}).distIntBits, base.distIntBits + 5);
  SimdOptions o;
  o.formats.fracBits = 12;
  const PrimaryPlan p = PlanPrimaryPass(scene, o);
  EXPECT_EQ(p.fracBits, 12);
  EXPECT_EQ(p.t.fracBits, 12);
  EXPECT_GT(p.tErrorBound, base.tErrorBound);
}

TEST(SimdPrimary, UncertainPixelsAreFlaggedAndRecomputed) {
  // Two coincident spheres: every pixel on them is a near tie.
  Scene scene = GenerateRandomSpheres({.count = 4, .seed = 7, .width = 32, .height = 32});
  scene.objects.push_back(scene.objects[0]);
  SimdOptions keep;
  keep.uncertain = UncertainPolicy::kKeep;
  const PrimaryPass kept = RunPrimaryPass(scene, keep);
  const auto want = SequentialHits(scene);
  int onFirst = 0;
  for (size_t i = 0; i < want.size(); ++i) {
    if (want[i].object != 0) continue;
    ++onFirst;
    EXPECT_TRUE(kept.matrix.flags[i] & kNearTie) << i;
    EXPECT_FALSE(kept.matrix.flags[i] & kRecomputed);
  }
  ASSERT_GT(onFirst, 0);
  EXPECT_GE(kept.tiePixels, onFirst);
  // Too few integer bits: the distances overflow and are flagged; recompute repairs them.
  SimdOptions narrow;
  narrow.formats.intBits = 2;
  const PrimaryPass repaired = RunPrimaryPass(scene, narrow);
  EXPECT_GT(repaired.overflowPixels, 0);
  EXPECT_EQ(repaired.recomputedPixels,
            std::count_if(repaired.matrix.flags.begin(), repaired.matrix.flags.end(), [](uint32_t f) { return f != 0; }));
  EXPECT_EQ(ObjectMismatches(repaired.matrix, want), 0);
  narrow.uncertain = UncertainPolicy::kFail;
  EXPECT_THROW(RunPrimaryPass(scene, narrow), UserError);
  // A grazing ray: a sphere whose silhouette passes exactly through a pixel centre.
  Scene graze = GenerateRandomSpheres({.count = 1, .seed = 1, .width = 33, .height = 33});
  const auto tracer = Tracer::Create(graze, TraceOptions{});
  const PrimaryRay centre = tracer->Rays().At(16, 16), side = tracer->Rays().At(16, 10);
  Sphere& s = std::get<Sphere>(graze.objects[0].shape);
  s.center = centre.origin + centre.direction * 10.0;
  // radius = distance from the centre to the ray through pixel (16, 10)
  const Vec3 f = s.center - side.origin;
  s.radius = Length(f - side.direction * Dot(f, side.direction));
  const PrimaryPass g = RunPrimaryPass(graze, keep);
  EXPECT_TRUE(g.matrix.flags[10 * 33 + 16] & kGrazing);
  EXPECT_FALSE(g.matrix.flags[16 * 33 + 16] & kGrazing);
}

}  // namespace
}  // namespace zephyr::simd

namespace zephyr::simd {
namespace {

// Soundness of the error bounds: at every fraction width, recompute must repair every pixel
// whose first object differs from the double tracer, and the flagged pixels are counted.
TEST(SimdPrimary, RecomputeRepairsEveryPixelAtLowWidths) {
  const Scene scene = GenerateRandomSpheres({.count = 64, .seed = 1, .width = 64, .height = 64});
  const auto want = SequentialHits(scene);
  int64_t previousFlagged = -1;
  for (int bits : {4, 6, 8, 12}) {
    SimdOptions o;
    o.formats.fracBits = bits;
    const PrimaryPass pass = RunPrimaryPass(scene, o);
    EXPECT_EQ(ObjectMismatches(pass.matrix, want), 0) << bits << " fraction bits";
    const int64_t flagged = std::count_if(pass.matrix.flags.begin(), pass.matrix.flags.end(),
                                          [](uint32_t f) { return f != 0; });
    EXPECT_EQ(pass.recomputedPixels, flagged);
    EXPECT_EQ(pass.Json()["uncertain"]["recomputed"].get<int64_t>(), flagged);
    EXPECT_GT(flagged, 0) << bits;  // at these widths some pixels are always uncertain
    if (previousFlagged >= 0) {
      EXPECT_LE(flagged, previousFlagged) << bits;  // wider: fewer
    }
    previousFlagged = flagged;
    // With `keep`, every pixel whose object differs is one the pass flagged.
    o.uncertain = UncertainPolicy::kKeep;
    const PrimaryPass kept = RunPrimaryPass(scene, o);
    int unflaggedWrong = 0, wrong = 0;
    for (size_t i = 0; i < want.size(); ++i)
      if (kept.matrix.hits[i].object != want[i].object) ++wrong, unflaggedWrong += kept.matrix.flags[i] == 0;
    EXPECT_EQ(unflaggedWrong, 0) << bits << " fraction bits, " << wrong << " wrong";
  }
}

TEST(SimdPrimary, TransformedPrimitivesRunOnTheArray) {
  const Scene scene = GenerateTransformedShowcase(64, 64);
  const PrimaryPass pass = RunPrimaryPass(scene, {});
  EXPECT_EQ(ObjectMismatches(pass.matrix, SequentialHits(scene)), 0);
  // Only the cones stay on the host; the ellipsoid's and polygons' divisions are on the array.
  for (int i : pass.plan.hostObjects) EXPECT_EQ(scene.objects[i].Kind(), ShapeKind::kCone);
  EXPECT_LT(pass.plan.hostObjects.size(), scene.objects.size() / 2);
  EXPECT_GT(pass.cycles["byOp"]["div"]["cycles"].get<double>(), 0) << pass.cycles.dump();
  const auto want = SequentialHits(scene);
  for (int bits : {6, 10, 16}) {
    SimdOptions o;
    o.formats.fracBits = bits;
    EXPECT_EQ(ObjectMismatches(RunPrimaryPass(scene, o).matrix, want), 0) << bits;
    // Unflagged pixels are right, and their t within the stated bound.
    o.uncertain = UncertainPolicy::kKeep;
    const PrimaryPass kept = RunPrimaryPass(scene, o);
    for (size_t i = 0; i < want.size(); ++i) {
      if (kept.matrix.flags[i] != 0) continue;
      ASSERT_EQ(kept.matrix.hits[i].object, want[i].object) << bits << " bits, pixel " << i;
      if (want[i].object >= 0 && scene.objects[want[i].object].Kind() != ShapeKind::kCone) {
        ASSERT_NEAR(kept.matrix.hits[i].t, want[i].t, kept.plan.tErrorBound) << bits << " bits, pixel " << i;
      }
    }
  }
}

}  // namespace
}  // namespace zephyr::simd
