// Several array passes (docs/simd.md, "Several array passes"): an image whose virtual PEs need
// more memory than the array's PEs hold runs in bands of rows, each a complete pass with its
// own layers, matrix readout and cycle report, plus the total.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "fixed/check.h"
#include "hosts/methods/report.h"
#include "hosts/scene/gen.h"
#include "hosts/scene/nff.h"
#include "hosts/simd/pass.h"
#include "hosts/trace/tracer.h"

namespace zephyr::simd {
namespace {

TEST(SimdPasses, ImageLargerThanTheArrayIsPlannedInBandsOfRows) {
  const Scene scene =
      GenerateRandomSpheres({.count = 64, .seed = 1, .width = 4096, .height = 4096});
  const PrimaryPlan plan = PlanPrimaryPass(scene, {});
  ASSERT_GT(plan.passes, 1);
  EXPECT_EQ(plan.pesPerPass % 4096, 0);  // whole rows
  EXPECT_GE(plan.pesPerPass * plan.passes, plan.virtualPes);
  EXPECT_LT(plan.pesPerPass * (plan.passes - 1), plan.virtualPes);
  EXPECT_EQ(plan.layers, 2048);  // 4096 rows of 4096 pixels, 8192 PEs a layer
  EXPECT_EQ(plan.layersPerPass, (plan.pesPerPass + 8191) / 8192);
  // Each pass's layers leave every virtual PE the memory the pass needs; one more pass's
  // worth of layers would not.
  EXPECT_LE(plan.memoryBitsPerPe, plan.internalCapacity + plan.externalCapacity);
  EXPECT_NE(plan.Text().find("array passes"), std::string::npos) << plan.Text();
}

// 128x96 pixels (2 layers) on a machine whose PEs hold one layer's program but not two: two
// passes of 48 rows. The matrix is that of one pass on the full machine, bit for bit, and its
// first objects are the sequential tracer's.
TEST(SimdPasses, TwoPassesGiveTheOnePassMatrixAndSeqsFirstHits) {
  const Scene scene = GenerateRandomSpheres({.count = 24, .seed = 3, .width = 128, .height = 96});
  SimdOptions o;
  o.uncertain = UncertainPolicy::kKeep;
  const PrimaryPass one = RunPrimaryPass(scene, o);
  ASSERT_EQ(one.plan.passes, 1);
  ASSERT_EQ(one.plan.layers, 2);
  const int64_t need = one.plan.memoryBitsPerPe;
  o.profileOverrides = {"internalBitsPerPe=" + std::to_string(need / 2),
                        "externalBitsPerPe=" + std::to_string(need)};
  const PrimaryPass two = RunPrimaryPass(scene, o);
  ASSERT_EQ(two.plan.passes, 2);
  EXPECT_EQ(two.plan.pesPerPass, 48 * 128);
  EXPECT_EQ(two.plan.layers, 2);
  EXPECT_EQ(two.matrix.flags, one.matrix.flags);
  for (size_t i = 0; i < one.matrix.hits.size(); ++i) {
    ASSERT_EQ(two.matrix.hits[i].object, one.matrix.hits[i].object) << i;
    ASSERT_EQ(two.matrix.hits[i].t, one.matrix.hits[i].t) << i;
  }
  // The report: each pass's own, and the total (typed, then as the report writes it).
  ASSERT_EQ(two.array.passes.size(), 2u);
  EXPECT_EQ(two.array.cycles.Runs(), 2);
  EXPECT_EQ(two.array.cycles.TotalCycles(),
            two.array.passes[0].cycles.TotalCycles() + two.array.passes[1].cycles.TotalCycles());
  EXPECT_EQ(two.array.passes[1].firstPe, 48 * 128);
  const nlohmann::json c = ArrayRunJson(two.array);
  ASSERT_EQ(c["passes"].size(), 2u) << c.dump();
  double total = 0;
  for (const nlohmann::json& p : c["passes"]) {
    EXPECT_EQ(p["cycles"]["layers"].get<int>(), 1);
    EXPECT_GT(p["cycles"]["byOp"]["hostRead"]["cycles"].get<double>(), 0);  // its own readout
    total += p["cycles"]["totalCycles"].get<double>();
  }
  EXPECT_EQ(c["passes"][1]["rows"][0].get<int>(), 48);
  EXPECT_DOUBLE_EQ(c["totalCycles"].get<double>(), total);
  EXPECT_EQ(c["layers"].get<int>(), 2);
  EXPECT_EQ(c["byLayer"].size(), 2u);
  EXPECT_NE(two.array.Table().find("array pass 2 of 2: rows 48..95"), std::string::npos)
      << two.array.Table();
  EXPECT_NE(two.array.Table().find("total over 2 array passes"), std::string::npos)
      << two.array.Table();

  // With recompute: every pixel's first object is the sequential tracer's.
  o.uncertain = UncertainPolicy::kRecompute;
  const PrimaryPass repaired = RunPrimaryPass(scene, o);
  ASSERT_EQ(repaired.plan.passes, 2);
  TraceOptions trace;
  trace.depth = 1;
  const auto seq = Tracer::Create(scene, trace);
  const PrimaryRays rays(scene.camera);
  TraceStats stats;
  int differ = 0, hits = 0;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 128; ++x) {
      const int want = seq->FirstHit(rays.At(x, y), stats).object;
      differ += repaired.matrix.hits[size_t(y) * 128 + x].object != want;
      hits += want >= 0;
    }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(hits, 128 * 96 / 10);
}

// The planner's memory is what the program allocates, for every kind and both number
// systems: on one layer of the WaveTracer (every temporary fits internal memory, the matrix
// is external) the pass's measured peak is the plan's figure exactly, and the largest
// object's temporaries are within it. (The sphere-only estimate it replaces said ~600 bits
// for the showcase's cones and ellipsoids, whose programs allocate ~770.)
TEST(SimdPasses, ThePlannedMemoryIsWhatTheProgramAllocates) {
  const std::string head =
      "b 0 0 0\nv\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 30\nhither 0.01\nresolution 32 32\nl 5 5 "
      "5\n"
      "f 1 0.5 0.2 0.7 0.3 10 0 1\n";
  struct Case {
    std::string name;
    Scene scene;
    NumberSystem number = NumberSystem::kFixed;
  };
  const std::vector<Case> cases = {
      {"spheres", GenerateRandomSpheres({.count = 8, .seed = 2, .width = 32, .height = 32})},
      {"showcase", GenerateTransformedShowcase(32, 32)},
      {"polygon", ParseNffOrThrow(head + "p 3\n-1 -1 0\n1 -1 0\n0 1 0\n", "poly.nff")},
      {"cone", ParseNffOrThrow(head + "c 0 0 0 1 0 1 0 0.5\n", "cone.nff")},
      {"float spheres", GenerateRandomSpheres({.count = 8, .seed = 2, .width = 32, .height = 32}),
       NumberSystem::kFloat}};
  for (const Case& c : cases) {
    SimdOptions o;
    o.uncertain = UncertainPolicy::kKeep;
    o.number = c.number;
    const PrimaryPass pass = RunPrimaryPass(c.scene, o);
    ASSERT_EQ(pass.array.passes.size(), 1u) << c.name;
    const ArrayPassReport& run = pass.array.passes[0];
    EXPECT_EQ(run.internalPeakBits + run.externalPeakBits, pass.plan.memoryBitsPerPe) << c.name;
    EXPECT_LE(run.externalPeakBits, pass.plan.matrixBitsPerPe) << c.name << ": a temporary spilled";
    int64_t widest = 0;
    for (const ObjectPlan& object : pass.plan.objects)
      widest = std::max(widest, object.temporaryBits);
    EXPECT_GT(widest, 0) << c.name;
    EXPECT_LE(pass.plan.matrixBitsPerPe + widest, pass.plan.memoryBitsPerPe) << c.name;
  }
}

// The split the planner makes always runs: a machine whose PEs hold the showcase's program
// with exactly its bits at two layers runs the 256x128 image (4 layers) in passes of at most
// two layers, one bit less in passes of one layer, and each gives the one-pass matrix.
TEST(SimdPasses, ThePlannedSplitRunsAtTheProgramsExactNeed) {
  const Scene scene = GenerateTransformedShowcase(256, 128);  // 4 layers
  SimdOptions o;
  o.uncertain = UncertainPolicy::kKeep;
  const PrimaryPass one = RunPrimaryPass(scene, o);
  ASSERT_EQ(one.plan.passes, 1);
  const int64_t need = one.plan.memoryBitsPerPe;
  for (const int64_t less : {0, 1}) {
    const int64_t internal = 2 * (need / 2), external = 2 * (need - need / 2) - 2 * less;
    o.profileOverrides = {"internalBitsPerPe=" + std::to_string(internal),
                          "externalBitsPerPe=" + std::to_string(external)};
    const PrimaryPass split = RunPrimaryPass(scene, o);
    EXPECT_LE(split.plan.layersPerPass, less ? 1 : 2) << less;
    EXPECT_GE(split.plan.passes, less ? 4 : 2) << less;
    EXPECT_EQ(split.plan.memoryBitsPerPe, need) << less;
    EXPECT_EQ(split.matrix.flags, one.matrix.flags) << less;
    for (size_t i = 0; i < one.matrix.hits.size(); ++i) {
      ASSERT_EQ(split.matrix.hits[i].object, one.matrix.hits[i].object) << i;
      ASSERT_EQ(split.matrix.hits[i].t, one.matrix.hits[i].t) << i;
    }
  }
}

TEST(SimdPasses, ARowWiderThanAPassIsAClearError) {
  // Rows of 8200 pixels on a machine whose PEs hold the program on one layer of 8192 PEs only.
  const Scene scene = GenerateRandomSpheres({.count = 4, .seed = 1, .width = 8200, .height = 2});
  SimdOptions o;
  const int64_t need = PlanPrimaryPass(scene, o).memoryBitsPerPe;
  o.profileOverrides = {"internalBitsPerPe=" + std::to_string(need / 2),
                        "externalBitsPerPe=" + std::to_string(need)};
  try {
    PlanPrimaryPass(scene, o);
    FAIL() << "an 8200-pixel row on one layer of 8192 PEs should not fit";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("a row of 8200 pixels does not fit"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace zephyr::simd
