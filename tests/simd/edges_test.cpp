// The SIMD pass's shared-edge rule (docs/simd.md, "Polygons"): on the array
// itself (--uncertain keep: no host recompute), a ray through an edge two polygons share is
// inside exactly one of them, for edges along x, y, z and a diagonal, convex and concave
// faces, folded or flat, wound either way (the cases of tests/trace/shared_edges.h): every
// pixel whose ray passes exactly through the edge or within 2.5 pixels of it meets one face,
// and no pixel meets both. Each face is a pass of its own, at the same explicit widths, so
// that both compute the same edge function bit for bit as they would in one scene.
#include <gtest/gtest.h>

#include "hosts/simd/pass.h"
#include "tests/trace/shared_edges.h"

namespace zephyr::simd {
namespace {

TEST(SimdSharedEdges, ARayThroughAnEdgeOnEveryAxisIsInsideExactlyOneFaceOnTheArray) {
  SimdOptions options;
  options.uncertain = UncertainPolicy::kKeep;
  options.formats.fracBits = 20;
  options.formats.dirFracBits = 20;
  options.formats.intBits = 6;
  options.threads = 1;
  for (const testing::SharedEdgeCase& c : testing::SharedEdgeCases()) {
    const PrimaryPass a = RunPrimaryPass(c.a, options), b = RunPrimaryPass(c.b, options);
    ASSERT_EQ(a.plan.fracBits, b.plan.fracBits) << c.name;
    ASSERT_EQ(a.plan.dirFracBits, b.plan.dirFracBits) << c.name;
    std::vector<int> hits(a.matrix.hits.size());
    int both = 0;
    for (size_t i = 0; i < hits.size(); ++i) {
      hits[i] = (a.matrix.hits[i].object >= 0) + 2 * (b.matrix.hits[i].object >= 0);
      both += hits[i] == 3;
    }
    EXPECT_EQ(both, 0) << c.name << ": pixels meeting both faces";
    int line = 0, seenA = 0, seenB = 0;
    for (const int i : c.line) line += hits[i] == 1 || hits[i] == 2;
    EXPECT_EQ(line, int(c.line.size())) << c.name << ": pixels on the edge meeting one face";
    for (const int i : c.band) {
      EXPECT_TRUE(hits[i] == 1 || hits[i] == 2) << c.name << ": pixel beside the edge " << i;
      seenA += hits[i] == 1, seenB += hits[i] == 2;
    }
    EXPECT_GE(seenA, 20) << c.name;
    EXPECT_GE(seenB, 20) << c.name;
  }
}

}  // namespace
}  // namespace zephyr::simd
