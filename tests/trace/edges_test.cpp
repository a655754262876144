// The host tracer's shared-edge rule (docs/shading.md, "Polygons"): a ray
// exactly through an edge two polygons share meets exactly one of them, for edges along x, y,
// z and a diagonal, convex and concave faces, folded or flat, wound either way, in float and
// double; rays near the edge likewise (no crack, no double hit), and rays through the edges a
// concave face's fan triangles share inside it meet that face once.
#include <gtest/gtest.h>

#include "hosts/trace/tracer.h"
#include "tests/trace/shared_edges.h"

namespace zephyr {
namespace {

bool Hits(const Tracer& tracer, const PrimaryRay& ray) {
  TraceStats stats;
  return tracer.FirstHit(ray, stats).object >= 0;
}

TEST(TraceSharedEdges, ARayThroughAnEdgeOnEveryAxisMeetsExactlyOneFace) {
  const std::vector<testing::SharedEdgeCase> cases = testing::SharedEdgeCases();
  ASSERT_EQ(cases.size(), 4u * 3 * 3 * 2);
  for (const Precision precision : {Precision::kFloat, Precision::kDouble}) {
    TraceOptions options;
    options.precision = precision;
    for (const testing::SharedEdgeCase& c : cases) {
      const std::string what = std::string(kPrecisionNames.NameOf(precision)) + ", " + c.name;
      const auto a = Tracer::Create(c.a, options), b = Tracer::Create(c.b, options);
      const PrimaryRays& rays = a->Rays();
      const int w = c.a.camera.width;
      std::vector<int> hits(size_t(w) * c.a.camera.height);
      int both = 0;
      for (size_t i = 0; i < hits.size(); ++i) {
        const PrimaryRay ray = rays.At(int(i % w), int(i / w));
        hits[i] = Hits(*a, ray) + 2 * Hits(*b, ray);
        both += hits[i] == 3;
      }
      EXPECT_EQ(both, 0) << what << ": pixels meeting both faces";
      ASSERT_GE(c.line.size(), 20u) << what;
      for (const int i : c.line) {
        EXPECT_TRUE(hits[i] == 1 || hits[i] == 2) << what << ": pixel on the edge " << i;
      }
      int seenA = 0, seenB = 0;
      for (const int i : c.band) {
        EXPECT_TRUE(hits[i] == 1 || hits[i] == 2) << what << ": pixel beside the edge " << i;
        seenA += hits[i] == 1, seenB += hits[i] == 2;
      }
      EXPECT_GE(seenA, 20) << what;
      EXPECT_GE(seenB, 20) << what;
      // Rays through points of the edge itself (not pixel centres), and beside it.
      int wrong = 0;
      for (int k = 3; k <= 61; ++k)
        for (const double nudge : {0.0, 1e-12, -1e-12}) {
          const Vec3 target =
              c.edgeFrom + (c.edgeTo - c.edgeFrom) * (k / 64.0) + Vec3{nudge, nudge, -nudge};
          const PrimaryRay ray{{0, 0, 0}, Normalize(target)};
          wrong += Hits(*a, ray) + Hits(*b, ray) != 1;
        }
      EXPECT_EQ(wrong, 0) << what << ": rays through points of the edge meeting no face or both";
      // Inside a concave face: the fan's own shared edges.
      for (const Vec3& p : c.diagonalPoints) {
        const PrimaryRay ray{{0, 0, 0}, Normalize(p)};
        EXPECT_TRUE(Hits(*a, ray) && !Hits(*b, ray))
            << what << ": a fan diagonal at " << p.x << " " << p.y << " " << p.z;
      }
    }
  }
}

}  // namespace
}  // namespace zephyr
