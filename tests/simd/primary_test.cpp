// The SIMD/sequential method's primary pass against the exact (128-bit) first-hit reference.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "fixed/check.h"
#include "hosts/scene/gen.h"
#include "hosts/scene/nff.h"
#include "hosts/simd/pass.h"
#include "hosts/trace/exact.h"

namespace zephyr::simd {
namespace {

// Every pixel's first object and t from the exact (128-bit) reference (hosts/trace/exact.h).
std::vector<PrimaryHit> ExactHits(const Scene& scene) {
  const PrimaryRays rays(scene.camera);
  const double tMin = std::max(scene.camera.hither, 0.0);
  std::vector<PrimaryHit> hits;
  const std::vector<int> planes = exact::CoplanarPolygons(scene);
  for (int y = 0; y < scene.camera.height; ++y)
    for (int x = 0; x < scene.camera.width; ++x) {
      const exact::Hit h = exact::FirstHit(scene, rays.At(x, y), tMin, planes);
      PrimaryHit hit;
      hit.object = h.object;
      hit.t = h.object >= 0 ? double(h.t) : 0.0;
      hits.push_back(hit);
    }
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
  EXPECT_EQ(ObjectMismatches(pass.matrix, ExactHits(scene)), 0);
  EXPECT_EQ(pass.plan.layers, 1);
  EXPECT_GT(pass.array.cycles.TotalCycles(), 0);
}

// A machine without external memory (the MPP's and BLITZEN's 1 Kbit per PE, a DRAM PIM's
// subarray rows) holds the matrix in internal memory: the pass runs there, with the same
// first objects (it was refused as not fitting, with 428 of 1024 bits needed).
TEST(SimdPrimary, AMachineWithoutExternalMemoryHoldsTheMatrixInternally) {
  const Scene scene = GenerateRandomSpheres({.count = 16, .seed = 1, .width = 64, .height = 64});
  const std::vector<PrimaryHit> exact = ExactHits(scene);
  for (const char* profile : {"mpp", "blitzen"}) {
    SCOPED_TRACE(profile);
    SimdOptions options;
    options.profile = profile;
    ASSERT_EQ(MachineProfileOf(options).externalBitsPerPe, 0);
    const PrimaryPass pass = RunPrimaryPass(scene, options);
    EXPECT_EQ(ObjectMismatches(pass.matrix, exact), 0);
    EXPECT_EQ(pass.array.passes.at(0).externalPeakBits, 0);
    EXPECT_GT(pass.array.passes.at(0).internalPeakBits, 0);
  }
}

// The machine profile is resolved once into the options (ResolveMachine) and every stage of
// the pass reads that: a profile file deleted after it was resolved still runs, with its
// overrides; a profile or an override changed afterwards is the one the pass uses, never the
// stale one.
TEST(SimdPrimary, TheMachineProfileIsResolvedOnceAndNeverStale) {
  const Scene scene = GenerateRandomSpheres({.count = 8, .seed = 1, .width = 32, .height = 32});
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("zephyr_resolved_" + std::to_string(::getpid()));
  std::ofstream(file) << bitserial::Profile("mpp").FileText();
  SimdOptions o;
  o.profile = file.string();
  o.profileOverrides = {"clockHz=2e7"};
  ResolveMachine(o);
  std::filesystem::remove(file);
  ASSERT_NE(o.machine, nullptr);
  EXPECT_EQ(MachineProfileOf(o).clockHz, 2e7);
  const PrimaryPass fromFile = RunPrimaryPass(scene, o);  // the file is gone: read once
  EXPECT_EQ(fromFile.array.cycles.Profile().clockHz, 2e7);
  SimdOptions mpp;
  mpp.profile = "mpp";
  mpp.profileOverrides = {"clockHz=2e7"};
  EXPECT_EQ(fromFile.array.cycles.TotalCycles(),
            RunPrimaryPass(scene, mpp).array.cycles.TotalCycles());
  // Changed after resolving: the new words win, in MachineProfileOf and in the pass.
  o.profile = "wavetracer";
  o.profileOverrides = {};
  EXPECT_EQ(MachineProfileOf(o).name, "wavetracer");
  EXPECT_EQ(RunPrimaryPass(scene, o).array.cycles.Profile().name, "wavetracer");
  o.profileOverrides = {"clockHz=3e7"};
  ResolveMachine(o);
  EXPECT_EQ(o.machine->clockHz, 3e7);
  EXPECT_EQ(RunPrimaryPass(scene, o).array.cycles.Profile().clockHz, 3e7);
}

TEST(SimdPrimary, FirstObjectAgreesOnEveryPixelSphereflake) {
  const Scene scene = GenerateSphereflake(2, 64, 64);  // 91 spheres and a floor polygon
  const PrimaryPass pass = RunPrimaryPass(scene, {});
  const auto want = ExactHits(scene);
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
    for (int x = 0; x < 16; ++x)
      ASSERT_EQ(part[size_t(y) * 16 + x], full[size_t(y + 4) * 40 + x + 8]);
}

TEST(SimdPrimary, SceneThatCannotFitIsAClearError) {
  // PEs of 1024 internal and 128 external bits cannot hold the pass at 40 fraction bits (the
  // matrix, in external memory, would need ~180): the planner refuses it with what the program
  // needs, why it does not fit, and a width that does fit — and the pass runs at that width.
  Scene scene = GenerateRandomSpheres({.count = 8, .seed = 1, .width = 64, .height = 64});
  SimdOptions o;
  o.uncertain = UncertainPolicy::kKeep;
  o.profileOverrides = {"internalBitsPerPe=1024", "externalBitsPerPe=128"};
  o.formats.fracBits = 40;
  try {
    PlanPrimaryPass(scene, o);
    FAIL() << "40 fraction bits should not fit one layer of 1024 + 128 bits";
  } catch (const UserError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("does not fit one layer"), std::string::npos) << what;
    EXPECT_NE(what.find("t and lengths s"), std::string::npos) << what;
    EXPECT_NE(what.find("PE memory full: multi 'matrix."), std::string::npos) << what;
    const size_t at = what.find(" fraction bits would fit");
    ASSERT_NE(at, std::string::npos) << what;
    o.formats.fracBits = std::stoi(what.substr(what.rfind(' ', at - 1) + 1));
    EXPECT_LT(o.formats.fracBits, 40);
    EXPECT_EQ(RunPrimaryPass(scene, o).plan.passes, 1);  // the width it names runs
    ++o.formats.fracBits;                                // and is the widest that does
    EXPECT_THROW(PlanPrimaryPass(scene, o), UserError);
  }
  // An MPP cut to 128 bits per PE and no external memory: no width fits (the matrix goes to
  // internal memory there, AMachineWithoutExternalMemoryHoldsTheMatrixInternally), and the
  // planner says so rather than passing a plan whose pass fails as it allocates.
  SimdOptions mpp;
  mpp.profile = "mpp";
  mpp.profileOverrides = {"internalBitsPerPe=128"};
  try {
    PlanPrimaryPass(scene, mpp);
    FAIL() << "128 bits per PE hold no width of the pass";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("no width down to 4 fraction bits fits"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("128 internal + 0 external"), std::string::npos)
        << e.what();
  }
}

TEST(SimdPrimary, PlannerFollowsTheSceneAndTheOverrides) {
  Scene scene = GenerateRandomSpheres({.count = 8, .seed = 1, .width = 384, .height = 384});
  const PrimaryPlan base = PlanPrimaryPass(scene, {});
  EXPECT_EQ(base.layers, 18);  // 147,456 rays = 18 × 8192 (paper §5.1)
  EXPECT_EQ(base.dirFracBits, base.fracBits);
  // Smaller spheres need more fraction bits; a farther scene more integer bits.
  Scene small = scene, far = scene;
  for (Primitive& p : small.objects) std::get<Sphere>(p.shape).radius /= 16;
  for (Primitive& p : far.objects)
    std::get<Sphere>(p.shape).centre = std::get<Sphere>(p.shape).centre * 64.0;
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
  const auto want = ExactHits(scene);
  int onFirst = 0;
  for (size_t i = 0; i < want.size(); ++i) {
    if (want[i].object != 0) continue;
    ++onFirst;
    EXPECT_TRUE(kept.matrix.flags[i] & kNearTie) << i;
    EXPECT_FALSE(kept.matrix.flags[i] & kRecomputed);
  }
  ASSERT_GT(onFirst, 0);
  EXPECT_GE(kept.uncertain.nearTie, onFirst);
  // Too few integer bits: the distances overflow and are flagged; recompute repairs them.
  SimdOptions narrow;
  narrow.formats.intBits = 2;
  const PrimaryPass repaired = RunPrimaryPass(scene, narrow);
  EXPECT_GT(repaired.uncertain.overflow, 0);
  EXPECT_EQ(repaired.recomputedPixels,
            std::count_if(repaired.matrix.flags.begin(), repaired.matrix.flags.end(),
                          [](uint32_t f) { return f != 0; }));
  EXPECT_EQ(ObjectMismatches(repaired.matrix, want), 0);
  narrow.uncertain = UncertainPolicy::kFail;
  EXPECT_THROW(RunPrimaryPass(scene, narrow), UserError);
  // A grazing ray: a sphere whose silhouette passes exactly through a pixel centre.
  Scene graze = GenerateRandomSpheres({.count = 1, .seed = 1, .width = 33, .height = 33});
  const auto tracer = Tracer::Create(graze, TraceOptions{});
  const PrimaryRay centre = tracer->Rays().At(16, 16), side = tracer->Rays().At(16, 10);
  Sphere& s = std::get<Sphere>(graze.objects[0].shape);
  s.centre = centre.origin + centre.direction * 10.0;
  // radius = distance from the centre to the ray through pixel (16, 10)
  const Vec3 f = s.centre - side.origin;
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
  const auto want = ExactHits(scene);
  int64_t previousFlagged = -1;
  for (int bits : {4, 6, 8, 12}) {
    SimdOptions o;
    o.formats.fracBits = bits;
    const PrimaryPass pass = RunPrimaryPass(scene, o);
    EXPECT_EQ(ObjectMismatches(pass.matrix, want), 0) << bits << " fraction bits";
    const int64_t flagged = std::count_if(pass.matrix.flags.begin(), pass.matrix.flags.end(),
                                          [](uint32_t f) { return f != 0; });
    EXPECT_EQ(pass.recomputedPixels, flagged);
    EXPECT_EQ(pass.recomputedPixels, flagged);
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
      if (kept.matrix.hits[i].object != want[i].object)
        ++wrong, unflaggedWrong += kept.matrix.flags[i] == 0;
    EXPECT_EQ(unflaggedWrong, 0) << bits << " fraction bits, " << wrong << " wrong";
  }
}

TEST(SimdPrimary, TransformedPrimitivesRunOnTheArray) {
  const Scene scene = GenerateTransformedShowcase(64, 64);
  const PrimaryPass pass = RunPrimaryPass(scene, {});
  EXPECT_EQ(ObjectMismatches(pass.matrix, ExactHits(scene)), 0);
  // Every primitive, cones included, is tested on the array (no host-tested objects): the
  // divisions run there, and the cone program's multi × multi products (its heights) too.
  EXPECT_GT(pass.array.cycles.OpCycles("mul"), 0) << pass.array.cycles.Json().dump();
  EXPECT_GT(pass.array.cycles.OpCycles("div"), 0) << pass.array.cycles.Json().dump();
  const auto want = ExactHits(scene);
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
      if (want[i].object >= 0) {
        ASSERT_NEAR(kept.matrix.hits[i].t, want[i].t, kept.plan.tErrorBound)
            << bits << " bits, pixel " << i;
      }
    }
  }
}

}  // namespace
}  // namespace zephyr::simd

// Cones and cylinders (NFF `c`) on the array: first-object agreement with the exact
// reference, sound flags at the planned and a low width, the cone ops in the report.
namespace zephyr::simd {
namespace {

Affine Move(double sx, double sy, double sz, Vec3 t) {
  Affine a;
  a.m[0][0] = sx, a.m[1][1] = sy, a.m[2][2] = sz;
  a.m[0][3] = t.x, a.m[1][3] = t.y, a.m[2][3] = t.z;
  return a;
}

Affine RotX(double deg) {
  const double c = std::cos(deg * M_PI / 180), s = std::sin(deg * M_PI / 180);
  Affine a;
  a.m[1][1] = c, a.m[1][2] = -s, a.m[2][1] = s, a.m[2][2] = c;
  return a;
}

// Cylinders and cones, plain and transformed, in front of each other, on a floor: a
// vertical cylinder, a cone to a point, a frustum, a tube seen nearly end-on (the ray almost
// parallel to the axis: A ≈ 0), a sheared cylinder, a cone rotated onto its side and
// squashed, a cylinder with negative radii (the mirrored nappe: never hit), and a sphere.
Scene ConeScene(int size) {
  Scene s;
  s.source = "cone test";
  s.camera = Camera{{0, -8, 2.5}, {0, 0, 0.8}, {0, 0, 1}, 40, 0.01, size, size};
  s.lights = {Light{{-5, -6, 8}, {1, 1, 1}}};
  s.materials = {Material{}};
  auto add = [&](Shape shape, std::optional<Affine> t = std::nullopt) {
    Primitive p;
    p.shape = std::move(shape);
    p.transform = t;
    s.objects.push_back(std::move(p));
  };
  add(Polygon{{{5, 5, 0}, {-5, 5, 0}, {-5, -5, 0}, {5, -5, 0}}, {}});
  add(Cone{{-1.6, 0.5, 0}, 0.5, {-1.6, 0.5, 1.8}, 0.5});    // cylinder
  add(Cone{{0.1, 0.2, 0}, 0.7, {0.1, 0.2, 1.9}, 0});        // cone to a point
  add(Cone{{1.7, 0.8, 0}, 0.3, {1.7, 0.8, 1.2}, 0.8});      // frustum, wider on top
  add(Cone{{0.6, -3.5, 2.1}, 0.35, {0.45, 3, 1.2}, 0.35});  // a tube along the view
  Affine shear;
  shear.m[0][2] = 0.4;
  add(Cone{{0, 0, 0}, 0.3, {0, 0, 1.4}, 0.3}, Move(1, 1, 1, {-0.6, -1.5, 0}) * shear);
  add(Cone{{0, 0, 0}, 0.5, {0, 0, 1.2}, 0.05},
      Move(1, 1, 1, {1.2, -1.8, 0.5}) * RotX(80) * Move(1.3, 0.7, 1, {}));
  add(Cone{{-2.5, -2, 0}, -0.3, {-2.5, -2, 1}, -0.3});  // never hit
  add(Sphere{{-0.7, 1.8, 0.6}, 0.6});
  return s;
}

// Every cone of the scene is seen by some pixel (else the test would prove little).
void ExpectEveryConeVisible(const Scene& scene, const std::vector<PrimaryHit>& want,
                            int skip = -1) {
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    if (scene.objects[i].Kind() != ShapeKind::kCone || int(i) == skip) continue;
    EXPECT_TRUE(std::any_of(want.begin(), want.end(),
                            [&](const PrimaryHit& h) { return h.object == int(i); }))
        << "cone " << i;
  }
}

void CheckScene(const Scene& scene, int neverHit) {
  const auto want = ExactHits(scene);
  ExpectEveryConeVisible(scene, want, neverHit);
  for (int bits : {-1, 8}) {  // planned, and 8 fraction bits
    SimdOptions o;
    o.formats.fracBits = bits;
    const PrimaryPass pass = RunPrimaryPass(scene, o);
    EXPECT_EQ(ObjectMismatches(pass.matrix, want), 0) << bits << " fraction bits";
    // The cone program's ops: multi × multi products (the heights) appear only for cones.
    EXPECT_GT(pass.array.cycles.OpCycles("mul"), 0) << pass.array.cycles.Json().dump();
    EXPECT_GT(pass.array.cycles.OpCycles("div"), 0);
    EXPECT_GT(pass.array.cycles.OpCycles("sqrt"), 0);
    // With `keep`: every unflagged pixel has the right object and t within the bound.
    o.uncertain = UncertainPolicy::kKeep;
    const PrimaryPass kept = RunPrimaryPass(scene, o);
    int coneCertain = 0, conePixels = 0;
    for (size_t i = 0; i < want.size(); ++i) {
      const bool cone =
          want[i].object >= 0 && scene.objects[want[i].object].Kind() == ShapeKind::kCone;
      conePixels += cone;
      if (kept.matrix.flags[i] != 0) continue;
      ASSERT_EQ(kept.matrix.hits[i].object, want[i].object) << bits << " bits, pixel " << i;
      if (want[i].object >= 0) {
        ASSERT_NEAR(kept.matrix.hits[i].t, want[i].t, kept.plan.tErrorBound)
            << bits << " bits, pixel " << i;
      }
      coneCertain += cone;
    }
    ASSERT_GT(conePixels, 0);
    if (bits < 0) {  // at the planned width the array decides a good share of cone pixels
      EXPECT_GE(coneCertain, conePixels / 4) << conePixels;
    } else {  // at 8 bits the bounds flag (nearly) everything: recompute does the work
      EXPECT_GT(kept.uncertain.grazing, int64_t(want.size()) / 2);
    }
  }
}

TEST(SimdCone, DedicatedSceneAgreesWithTheExactReference) { CheckScene(ConeScene(64), 7); }

TEST(SimdCone, ShowcaseAgreesWithTheExactReference) {
  CheckScene(GenerateTransformedShowcase(64, 64), -1);
}

TEST(SimdCone, PlanListsTheConeFormats) {
  const PrimaryPlan plan = PlanPrimaryPass(ConeScene(32), {});
  bool listed = false;
  for (const PlannedFormat& f : plan.formats)
    listed |= f.quantity.find("cone") != std::string::npos;
  EXPECT_TRUE(listed) << plan.Text();
  EXPECT_TRUE(std::isfinite(plan.tErrorBound));
  EXPECT_GT(plan.tErrorBound, 0);
}

// The pass-wide table comes from the object programs: a kind's rows appear when the scene has
// that kind, each at the widest format an object of the kind uses, and no other kind's.
TEST(SimdPlan, TheTableHoldsTheKindsTheSceneHasAtTheirWidestFormats) {
  Scene polygon = ConeScene(32);
  polygon.objects.resize(1);  // the floor polygon alone
  const PrimaryPlan one = PlanPrimaryPass(polygon, {});
  for (const PlannedFormat& f : one.formats) {
    EXPECT_EQ(f.quantity.find("sphere"), std::string::npos) << one.Text();
    EXPECT_EQ(f.quantity.find("cone"), std::string::npos) << one.Text();
    EXPECT_EQ(f.quantity.find("discriminant"), std::string::npos) << one.Text();
  }
  int polygonRows = 0;
  for (const PlannedFormat& f : one.formats) polygonRows += f.quantity.rfind("polygon: ", 0) == 0;
  EXPECT_EQ(size_t(polygonRows), one.objects[0].formats.size()) << one.Text();
  // Spheres of several sizes: each sphere row is the widest of the spheres' own.
  const Scene spheres = GenerateRandomSpheres({.count = 12, .seed = 2, .width = 32, .height = 32});
  const PrimaryPlan many = PlanPrimaryPass(spheres, {});
  bool any = false;
  for (const PlannedFormat& row : many.formats) {
    if (row.quantity.rfind("sphere: ", 0) != 0) continue;
    any = true;
    int widest = 0;
    for (const ObjectPlan& o : many.objects)
      for (const PlannedFormat& f : o.formats)
        if ("sphere: " + f.quantity == row.quantity) widest = std::max(widest, f.format.Width());
    EXPECT_EQ(row.format.Width(), widest) << row.quantity;
  }
  EXPECT_TRUE(any) << many.Text();
  EXPECT_EQ(many.formats.back().quantity, "object index + 1");
}

}  // namespace
}  // namespace zephyr::simd

// The refine pass (--uncertain refine): the uncertain pixels run again on the array at wider
// formats; what it certifies must be right (no pixel it leaves unflagged and unrecomputed
// differs from the exact reference), it runs on fewer PEs than the first pass, and it
// leaves fewer pixels to the host than recompute alone.
namespace zephyr::simd {
namespace {

void CheckRefine(const Scene& scene, int fracBits) {
  const auto want = ExactHits(scene);
  SimdOptions o;
  o.formats.fracBits = fracBits;
  o.uncertain = UncertainPolicy::kRefine;
  const PrimaryPass pass = RunPrimaryPass(scene, o);
  const int64_t first = pass.uncertain.overflow + pass.uncertain.grazing + pass.uncertain.nearTie;
  ASSERT_GT(first, 0) << "the scene should have uncertain pixels at " << fracBits << " bits";
  ASSERT_GT(pass.RefinedPixels(), 0);
  EXPECT_LE(pass.RefinedPixels(), first);
  EXPECT_LT(pass.RefinedPixels(), pass.plan.virtualPes);
  EXPECT_EQ(pass.refine->fracBits, std::min(pass.plan.fracBits + kRefineExtraBits, 56));
  EXPECT_EQ(pass.recomputedPixels, pass.refine->stillUncertain);
  EXPECT_LT(pass.recomputedPixels, pass.RefinedPixels()) << "refine certified nothing";
  EXPECT_EQ(ObjectMismatches(pass.matrix, want), 0);
  for (size_t i = 0; i < want.size(); ++i) {
    if (pass.matrix.flags[i] & kRecomputed) continue;
    ASSERT_EQ(pass.matrix.hits[i].object, want[i].object) << fracBits << " bits, pixel " << i;
  }
  EXPECT_GT(pass.refine->array.cycles.TotalCycles(), 0);
}

TEST(SimdRefine, CertifiesSoundlyOnSpheresAtLowAndPlannedWidths) {
  const Scene scene = GenerateRandomSpheres({.count = 64, .seed = 1, .width = 64, .height = 64});
  CheckRefine(scene, 8);
  CheckRefine(scene, -1);
}

TEST(SimdRefine, CertifiesSoundlyOnConesEllipsoidsAndPolygons) {
  CheckRefine(ConeScene(48), 10);
  CheckRefine(GenerateTransformedShowcase(48, 48), -1);
}

// auto refines exactly where the first pass flags more than kAutoRefineShare of the pixels
// (then as refine does), else recomputes (as recompute does).
TEST(SimdRefine, AutoRefinesOnlyAboveTheHostBudget) {
  const Scene scene = GenerateRandomSpheres({.count = 64, .seed = 1, .width = 64, .height = 64});
  for (int bits : {8, -1}) {
    SimdOptions o;
    o.formats.fracBits = bits;
    o.uncertain = UncertainPolicy::kAuto;
    const PrimaryPass automatic = RunPrimaryPass(scene, o);
    const int64_t flagged =
        automatic.uncertain.overflow + automatic.uncertain.grazing + automatic.uncertain.nearTie;
    ASSERT_GT(flagged, 0) << bits;
    const bool above = double(flagged) > kAutoRefineShare * 64 * 64;
    EXPECT_EQ(above, bits == 8) << "the case should have " << (bits == 8 ? "many" : "few")
                                << " flags: " << flagged;
    o.uncertain = above ? UncertainPolicy::kRefine : UncertainPolicy::kRecompute;
    const PrimaryPass same = RunPrimaryPass(scene, o);
    EXPECT_EQ(automatic.RefinedPixels(), same.RefinedPixels()) << bits;
    EXPECT_EQ(automatic.recomputedPixels, same.recomputedPixels) << bits;
    EXPECT_EQ(above, automatic.RefinedPixels() > 0) << bits;
    for (size_t i = 0; i < same.matrix.hits.size(); ++i)
      ASSERT_EQ(automatic.matrix.hits[i].object, same.matrix.hits[i].object)
          << bits << " bits, pixel " << i;
  }
}

TEST(SimdRefine, EveryPolicyAndNumberSystemHasOneNameThatParsesBack) {
  for (const auto& e : kUncertainPolicyNames.entries)
    EXPECT_EQ(kUncertainPolicyNames.Find(kUncertainPolicyNames.NameOf(e.value)), e.value) << e.name;
  for (const auto& e : kNumberSystemNames.entries)
    EXPECT_EQ(kNumberSystemNames.Find(kNumberSystemNames.NameOf(e.value)), e.value) << e.name;
  EXPECT_EQ(kUncertainPolicyNames.List(),
            "auto, recompute, refine, keep or fail");  // --help's order
  EXPECT_FALSE(kUncertainPolicyNames.Find("refin").has_value());
}

}  // namespace
}  // namespace zephyr::simd

namespace zephyr::simd {
namespace {

// The near root counts only beyond hither (docs/simd.md): a sphere the hither plane cuts
// shows its far side where its near side is closer than hither, on the array as in the exact
// reference — first object and t — with the eye outside the sphere, and with hither 0 the
// near side itself.
TEST(SimdPrimary, ANearRootInsideHitherGivesTheFarRoot) {
  for (double hither : {0.0, 4.0, 5.0, 5.9}) {
    const std::string text = "b 0 0 0\nv\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 20\nhither " +
                             std::to_string(hither) +
                             "\nresolution 32 32\nf 1 1 1 1 0 0 0 0\ns 0 0 5 1\ns 0 0 -3 0.5\n";
    const Scene scene = ParseNffOrThrow(text, "hither.nff");
    const PrimaryPass pass = RunPrimaryPass(scene, {});
    const std::vector<PrimaryHit> want = ExactHits(scene);
    int farSide = 0;
    for (size_t i = 0; i < want.size(); ++i) {
      if (pass.matrix.flags[i] & kUncertainFlags)
        continue;  // recomputed on the host: not the array's answer
      EXPECT_EQ(pass.matrix.hits[i].object, want[i].object)
          << "hither " << hither << " pixel " << i;
      if (want[i].object >= 0) {
        EXPECT_NEAR(pass.matrix.hits[i].t, want[i].t, 1e-2)
            << "hither " << hither << " pixel " << i;
        farSide += want[i].object == 0 && want[i].t > 5;
      }
    }
    if (hither > 4.1) {
      EXPECT_GT(farSide, 0) << "no pixel saw the sphere's far side at hither " << hither;
    }
  }
}

}  // namespace
}  // namespace zephyr::simd
