// The primary pass in layer blocks on host threads (bitserial/blocks.h, docs/simd.md, "Layer
// blocks and threads"): the matrix, the flags and the cycle report are exactly those of op-by-op
// execution over the whole machine, for any block size and 1, 2 or 4 threads, on scenes with
// every primitive kind; the host recompute gives the same pixels on any thread count.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "hosts/methods/report.h"
#include "hosts/scene/gen.h"
#include "hosts/simd/pass.h"

namespace zephyr::simd {
namespace {

// The transformed showcase (ellipsoid, cones, polygons) with a plain sphere added, over more
// than three layers (the last one partial): 160x160 = 25600 virtual PEs, 4 layers of 8192.
Scene EveryKind() {
  Scene s = GenerateTransformedShowcase(160, 160);
  Primitive sphere;
  sphere.shape = Sphere{{-0.4, -1.6, 0.5}, 0.5};
  s.objects.push_back(sphere);
  return s;
}

// The report without what depends on the host's speed (timing).
nlohmann::json Untimed(const PrimaryPass& pass) {
  nlohmann::json j = PrimaryPassJson(pass);
  for (nlohmann::json* k : {&j, &j["cycles"]})
    for (const char* key : {"hostSeconds", "realTimeFactor", "recomputeSeconds"}) k->erase(key);
  if (j.contains("refine"))
    for (nlohmann::json* k : {&j["refine"], &j["refine"]["cycles"]})
      for (const char* key : {"hostSeconds", "realTimeFactor"}) k->erase(key);
  return j;
}

// The cycle table without its last line (host time and real-time factor).
std::string UntimedTable(const std::string& table) {
  const size_t end = table.rfind('\n', table.size() - 2);
  return table.substr(0, end);
}

// Bit for bit: object, t and direction of every pixel, and its flags.
void ExpectSameMatrix(const PrimaryMatrix& a, const PrimaryMatrix& b, const std::string& what) {
  ASSERT_EQ(a.hits.size(), b.hits.size()) << what;
  ASSERT_EQ(a.flags, b.flags) << what;
  for (size_t i = 0; i < a.hits.size(); ++i) {
    const PrimaryHit &x = a.hits[i], &y = b.hits[i];
    ASSERT_EQ(x.object, y.object) << what << ", pixel " << i;
    ASSERT_EQ(std::memcmp(&x.t, &y.t, sizeof x.t), 0) << what << ", pixel " << i;
    for (int k = 0; k < 3; ++k) {
      const double dx = x.direction[k], dy = y.direction[k];
      ASSERT_EQ(std::memcmp(&dx, &dy, sizeof dx), 0) << what << ", pixel " << i;
    }
  }
}

void ExpectSamePass(const PrimaryPass& a, const PrimaryPass& b, const std::string& what) {
  ExpectSameMatrix(a.matrix, b.matrix, what);
  EXPECT_EQ(Untimed(a).dump(), Untimed(b).dump()) << what;
  EXPECT_EQ(UntimedTable(a.array.Table()), UntimedTable(b.array.Table())) << what;
}

void CheckBlocksAgainstOpByOp(const Scene& scene, SimdOptions o) {
  o.blockLayers = 1 << 20;  // one block: op by op over the whole machine
  o.threads = 1;
  const PrimaryPass whole = RunPrimaryPass(scene, o);
  ASSERT_GE(whole.plan.layers, 3);
  ASSERT_GT(whole.uncertain.grazing, 0);  // flags to compare, not only hits
  for (const auto& [layers, threads] : {std::pair{1, 1}, {1, 2}, {1, 4}, {2, 2}, {3, 4}}) {
    o.blockLayers = layers, o.threads = threads;
    ExpectSamePass(
        whole, RunPrimaryPass(scene, o),
        std::to_string(layers) + " layer(s) per block, " + std::to_string(threads) + " thread(s)");
  }
}

TEST(SimdBlocks, EveryKindSameMatrixFlagsAndReportAsOpByOp) {
  SimdOptions o;
  o.uncertain = UncertainPolicy::kKeep;  // the array's own answer at every pixel
  CheckBlocksAgainstOpByOp(EveryKind(), o);
}

TEST(SimdBlocks, LowWidthsSameAsOpByOp) {  // most pixels flagged: overflow and ties too
  SimdOptions o;
  o.uncertain = UncertainPolicy::kKeep;
  o.formats.fracBits = 6;
  CheckBlocksAgainstOpByOp(
      GenerateRandomSpheres({.count = 24, .seed = 7, .width = 150, .height = 150}), o);
}

TEST(SimdBlocks, RecomputeAndRefineSameOnAnyThreadCount) {
  const Scene scene = EveryKind();
  for (UncertainPolicy policy : {UncertainPolicy::kRecompute, UncertainPolicy::kRefine}) {
    SimdOptions o;
    o.uncertain = policy;
    o.formats.fracBits = 8;  // many uncertain pixels for the host (and the refine pass)
    o.threads = 1;
    const PrimaryPass one = RunPrimaryPass(scene, o);
    ASSERT_GT(policy == UncertainPolicy::kRefine ? one.RefinedPixels() : one.recomputedPixels, 0)
        << kUncertainPolicyNames.NameOf(policy);
    for (int threads : {2, 4}) {
      o.threads = threads;
      ExpectSamePass(one, RunPrimaryPass(scene, o),
                     std::string(kUncertainPolicyNames.NameOf(policy)) + ", " +
                         std::to_string(threads) + " threads");
    }
  }
}

}  // namespace
}  // namespace zephyr::simd
