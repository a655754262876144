// Several array passes (docs/simd.md, "Several array passes"): an image whose virtual PEs need
// more memory than the array's PEs hold runs in bands of rows, each a complete pass with its
// own layers, matrix readout and cycle report, plus the total.
#include <gtest/gtest.h>

#include <string>

#include "fixed/check.h"
#include "hosts/scene/gen.h"
#include "hosts/methods/report.h"
#include "hosts/simd/pass.h"
#include "hosts/trace/tracer.h"

namespace zephyr::simd {
namespace {

TEST(SimdPasses, ImageLargerThanTheArrayIsPlannedInBandsOfRows) {
  const Scene scene = GenerateRandomSpheres({.count = 64, .seed = 1, .width = 4096, .height = 4096});
  const PrimaryPlan plan = PlanPrimaryPass(scene, {});
  ASSERT_GT(plan.passes, 1);
  EXPECT_EQ(plan.pesPerPass % 4096, 0);  // whole rows
  EXPECT_GE(plan.pesPerPass * plan.passes, plan.virtualPes);
  EXPECT_LT(plan.pesPerPass * (plan.passes - 1), plan.virtualPes);
  EXPECT_EQ(plan.layers, 2048);          // 4096 rows of 4096 pixels, 8192 PEs a layer
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
  o.profileOverrides = {"internalBitsPerPe=" + std::to_string(need / 2), "externalBitsPerPe=" + std::to_string(need)};
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
  EXPECT_NE(two.array.Table().find("array pass 2 of 2: rows 48..95"), std::string::npos) << two.array.Table();
  EXPECT_NE(two.array.Table().find("total over 2 array passes"), std::string::npos) << two.array.Table();

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

// The planner's memory estimate is below what the showcase's cone and ellipsoid programs
// allocate: on a machine where two layers leave each virtual PE the estimate but not the real
// need, the pass splits again by what the program allocates (one layer per pass) instead of
// running out of memory, and the matrix is still the one-pass matrix.
TEST(SimdPasses, PassesSplitAgainWhenTheProgramNeedsMoreThanTheEstimate) {
  const Scene scene = GenerateTransformedShowcase(256, 128);  // 4 layers
  SimdOptions o;
  o.uncertain = UncertainPolicy::kKeep;
  const PrimaryPass one = RunPrimaryPass(scene, o);
  const int64_t estimate = PlanPrimaryPass(scene, o).memoryBitsPerPe;
  ASSERT_EQ(one.plan.passes, 1);
  const int64_t internal = estimate / 2, external = 2 * estimate + 16 - internal;
  o.profileOverrides = {"internalBitsPerPe=" + std::to_string(internal), "externalBitsPerPe=" + std::to_string(external)};
  const PrimaryPlan planned = PlanPrimaryPass(scene, o);
  ASSERT_EQ(planned.passes, 2);  // two layers each, by the estimate
  const PrimaryPass split = RunPrimaryPass(scene, o);
  EXPECT_EQ(split.plan.passes, 4);
  EXPECT_EQ(split.plan.layersPerPass, 1);
  EXPECT_GT(split.plan.memoryBitsPerPe, estimate);
  EXPECT_EQ(split.matrix.flags, one.matrix.flags);
  for (size_t i = 0; i < one.matrix.hits.size(); ++i) {
    ASSERT_EQ(split.matrix.hits[i].object, one.matrix.hits[i].object) << i;
    ASSERT_EQ(split.matrix.hits[i].t, one.matrix.hits[i].t) << i;
  }
}

TEST(SimdPasses, ARowWiderThanAPassIsAClearError) {
  // Rows of 8200 pixels on a machine whose PEs hold the program on one layer of 8192 PEs only.
  const Scene scene = GenerateRandomSpheres({.count = 4, .seed = 1, .width = 8200, .height = 2});
  SimdOptions o;
  const int64_t need = PlanPrimaryPass(scene, o).memoryBitsPerPe;
  o.profileOverrides = {"internalBitsPerPe=" + std::to_string(need / 2), "externalBitsPerPe=" + std::to_string(need)};
  try {
    PlanPrimaryPass(scene, o);
    FAIL() << "an 8200-pixel row on one layer of 8192 PEs should not fit";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("a row of 8200 pixels does not fit"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace zephyr::simd
