// Tests for the host tracer's hierarchy (--accel bvh, hosts/trace/bvh.h; docs/shading.md,
// "The BVH"): the same first hits (object and bits of t), shadow products and pixels as the
// exhaustive tracer on random spheres, coincident and touching spheres (ties), polygons
// sharing edges, transformed quadrics and every sample scene; the counted node visits of a
// hand-built scene; PNGs of every host-tracing method byte-equal with and without it.
#include "hosts/trace/bvh.h"

#include <gtest/gtest.h>

#include <bit>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "hosts/scene/gen.h"
#include "hosts/scene/nff.h"
#include "hosts/trace/tracer.h"
#include "tests/farm/mpi_launch.h"
#include "tests/trace/shared_edges.h"

namespace zephyr {
namespace {

std::unique_ptr<Tracer> Make(const Scene& scene, Accel accel,
                             Precision precision = Precision::kDouble, int depth = 5) {
  TraceOptions o;
  o.accel = accel;
  o.precision = precision;
  o.depth = depth;
  return Tracer::Create(scene, o);
}

uint64_t Bits(double v) { return std::bit_cast<uint64_t>(v); }

// Every pixel (colour bits, primary object and t bits) of both tracers, and the pixel count
// whose primary ray hit something (so a test cannot pass on an empty view).
int ExpectSameImage(const Tracer& none, const Tracer& bvh) {
  const Camera& c = none.GetScene().camera;
  std::vector<Vec3> a, b;
  std::vector<PrimaryHit> ha, hb;
  TraceStats sa, sb;
  RenderRegion(none, 0, 0, c.width, c.height, a, sa, &ha);
  RenderRegion(bvh, 0, 0, c.width, c.height, b, sb, &hb);
  int hits = 0, wrong = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    hits += ha[i].object >= 0;
    const bool same = ha[i].object == hb[i].object && Bits(ha[i].t) == Bits(hb[i].t) &&
                      Bits(a[i].x) == Bits(b[i].x) && Bits(a[i].y) == Bits(b[i].y) &&
                      Bits(a[i].z) == Bits(b[i].z);
    if (!same && ++wrong <= 5)
      ADD_FAILURE() << "pixel " << i << ": object " << ha[i].object << " t " << ha[i].t
                    << " exhaustive, object " << hb[i].object << " t " << hb[i].t << " bvh";
  }
  EXPECT_EQ(wrong, 0);
  // Every ray the exhaustive tracer shot, the hierarchy shot too (the same ray tree).
  for (int k = 0; k < kRayKinds; ++k) EXPECT_EQ(sa.rays[k], sb.rays[k]) << kRayKindNames[k];
  EXPECT_EQ(sa.hits, sb.hits);
  EXPECT_EQ(sa.nodeVisits, 0u);
  EXPECT_GT(sb.nodeVisits, 0u);
  return hits;
}

// Rays from `count` random points of the box [lo, hi] in random directions: the same first
// hit (hither as tMin, the point as origin), and from each point to every light the same
// shadow product bits at tMin 1e-9. Returns how many rays hit and how many products were
// strictly between 0 and 1 (light through a transparent surface).
struct RandomRayCounts {
  int hits = 0, partial = 0;
};
RandomRayCounts ExpectSameRandomRays(const Tracer& none, const Tracer& bvh, const Vec3& lo,
                                     const Vec3& hi, int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> g(0, 1);
  RandomRayCounts n;
  TraceStats sa, sb;
  const int lights = int(none.GetScene().lights.size());
  for (int i = 0; i < count; ++i) {
    const Vec3 p{lo.x + u(rng) * (hi.x - lo.x), lo.y + u(rng) * (hi.y - lo.y),
                 lo.z + u(rng) * (hi.z - lo.z)};
    const Vec3 d = Normalize(Vec3{g(rng), g(rng), g(rng)});
    const PrimaryHit a = none.FirstHit({p, d}, sa), b = bvh.FirstHit({p, d}, sb);
    EXPECT_EQ(a.object, b.object) << "ray " << i;
    EXPECT_EQ(Bits(a.t), Bits(b.t)) << "ray " << i;
    n.hits += a.object >= 0;
    for (int l = 0; l < lights; ++l) {
      const double ta = none.LightThrough(p, l, 1e-9, sa), tb = bvh.LightThrough(p, l, 1e-9, sb);
      EXPECT_EQ(Bits(ta), Bits(tb)) << "ray " << i << " light " << l << ": " << ta << " vs " << tb;
      n.partial += ta > 0 && ta < 1;
    }
  }
  return n;
}

// A scene on black seen from `from` toward `at` (up +y, hither 0) at size × size pixels
// with the vertical angle `angle` (degrees), then `rest` (NFF lights, materials, objects).
Scene Nff(const std::string& from, const std::string& at, int angle, int size,
          const std::string& rest) {
  return ParseNffOrThrow("b 0 0 0\nv\nfrom " + from + "\nat " + at + "\nup 0 1 0\nangle " +
                             std::to_string(angle) + "\nhither 0\nresolution " +
                             std::to_string(size) + " " + std::to_string(size) + "\n" + rest,
                         "test.nff");
}

Bounds SceneBox(const Scene& s) {
  Bounds b;
  for (const Primitive& p : s.objects) b.Grow(WorldBound(p));
  return b;
}

TEST(Bvh, RandomSpheresGiveTheExhaustiveHitsAndShadows) {
  for (const int count : {1, 7, 64, 500}) {
    SCOPED_TRACE(count);
    const Scene s = GenerateRandomSpheres({.count = count, .seed = 11, .width = 48, .height = 40});
    for (const Precision p : {Precision::kDouble, Precision::kFloat}) {
      const auto none = Make(s, Accel::kNone, p), bvh = Make(s, Accel::kBvh, p);
      EXPECT_GT(ExpectSameImage(*none, *bvh), 0);
      const Bounds box = SceneBox(s);
      const RandomRayCounts n = ExpectSameRandomRays(*none, *bvh, box.lo, box.hi, 400, 5);
      EXPECT_GT(n.hits, 0);
    }
  }
}

// 400 overlapping glass spheres, each with its own transparency T in [0.3, 0.95]: a shadow
// ray crosses several, and a product of unequal factors rounds differently in another
// order, so only the exhaustive loop's order (object order) gives the same bits.
TEST(Bvh, TransparentShadowProductsMatchBitForBit) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(0, 1);
  std::string objects;
  for (int i = 0; i < 400; ++i) {
    objects += "f 1 1 1 0.5 0.1 10 " + std::to_string(0.3 + 0.65 * u(rng)) + " 1.3\n";
    objects += "s " + std::to_string(8 * u(rng) - 4) + " " + std::to_string(8 * u(rng) - 4) + " " +
               std::to_string(8 * u(rng) - 4) + " " + std::to_string(0.3 + 0.5 * u(rng)) + "\n";
  }
  const Scene s = Nff("0 0 12", "0 0 0", 40, 8, "l 0 9 0\nl 7 -7 7\nl -3 0 -9\n" + objects);
  const auto none = Make(s, Accel::kNone), bvh = Make(s, Accel::kBvh);
  const RandomRayCounts n = ExpectSameRandomRays(*none, *bvh, {-4, -4, -4}, {4, 4, 4}, 3000, 9);
  EXPECT_GT(n.partial, 1000);
  // And the order matters here: the same crossings multiplied in reverse order differ in
  // some product (so the test above could catch a walk that multiplied in visiting order).
  int differ = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    double f[6], forward = 1, backward = 1;
    for (double& x : f) x = 0.3 + 0.65 * u(rng);
    for (int i = 0; i < 6; ++i) forward *= f[i];
    for (int i = 5; i >= 0; --i) backward *= f[i];
    differ += forward != backward;
  }
  EXPECT_GT(differ, 100);
}

// Coincident spheres (the same centre and radius: equal t, the lower index wins), spheres
// nested to touch at one point on an axis ray (equal t from different boxes and subtrees:
// centre (0,0,-5) r 1 and (0,0,-6) r 2 both meet the ray from the origin along −z at t = 4
// exactly), and spheres touching side by side; more copies than a leaf holds.
TEST(Bvh, CoincidentAndTouchingSpheresTieToTheLowerIndex) {
  std::string objects = "f 1 0 0 1 0 0 0.5 1.5\n";
  for (int copy = 0; copy < 7; ++copy) objects += "s 0 0 -5 1\n";  // coincident
  objects += "s 0 0 -6 2\ns 0 0 -7 3\n";                           // nested, touching at z = -4
  for (int i = 0; i < 5; ++i) {                                    // touching in a row
    objects += "s " + std::to_string(-4 + 2 * i) + " 3 -6 1\n";
    objects += "s " + std::to_string(-4 + 2 * i) + " 3 -6 1\n";
  }
  objects += "s 3 -3 -4 1\ns 3 -3 -5 2\ns 3 -3 -4 1\n";
  const Scene s = Nff("0 0 0", "0 0 -1", 60, 61, "l 0 10 0\nl 5 -5 5\n" + objects);
  const auto none = Make(s, Accel::kNone), bvh = Make(s, Accel::kBvh);
  EXPECT_GT(ExpectSameImage(*none, *bvh), 0);
  TraceStats stats;
  const PrimaryHit axis = bvh->FirstHit({{0, 0, 0}, {0, 0, -1}}, stats);
  EXPECT_EQ(axis.object, 0);  // seven coincident spheres and two nested ones at t = 4
  EXPECT_EQ(axis.t, 4.0);
  const Bounds box = SceneBox(s);
  ExpectSameRandomRays(*none, *bvh, box.lo, box.hi, 2000, 3);
  // Rays along the touching points: through (x, 3, -6) with x between the row's spheres.
  for (int i = 0; i < 4; ++i) {
    const Vec3 touch{-3.0 + 2 * i, 3, -6};
    for (const Vec3 from : {Vec3{0, 0, 0}, Vec3{-3.0 + 2 * i, 10, -6}, Vec3{-3.0 + 2 * i, 3, 5}}) {
      const Vec3 d = Normalize(touch - from);
      const PrimaryHit a = none->FirstHit({from, d}, stats), b = bvh->FirstHit({from, d}, stats);
      EXPECT_EQ(a.object, b.object);
      EXPECT_EQ(Bits(a.t), Bits(b.t));
    }
  }
}

// A tie between two leaves: object 0 a square in the plane z = −4 (100 wide), objects 1–3
// unit spheres, 1 centred at (0, 0, −5) touching the square at (0, 0, −4), 2 and 3 at
// (0, ±3, −5.5). The ray from the origin along −z meets the square and sphere 1 at t = 4
// exactly (the plane: (−4 − 0)/−1; the sphere: b = 5, disc = 1, c/q = 24/6). The build (by
// hand, SAH with a visit costing 2 tests): on z the best split is spheres | square, 10123
// against a leaf of 4: 2 + 10123/10500 < 4; the three spheres stay one leaf (the best split
// of them, 2 + 84/41, exceeds 3): 3 nodes. The spheres, the lower centroids on z, are the
// left child; both boxes are entered at 4 − pad, so the walk tests the spheres first and
// must then hand the tie to the square, the lower index, as the exhaustive loop does.
TEST(Bvh, ATieAcrossLeavesGoesToTheLowerIndex) {
  const Scene s =
      Nff("0 0 0", "0 0 -1", 40, 5,
          "l 0 0 10\nf 1 1 1 1 0 0 0 1\np 4\n-50 -50 -4\n50 -50 -4\n50 50 -4\n-50 50 -4\n"
          "s 0 0 -5 1\ns 0 3 -5.5 1\ns 0 -3 -5.5 1\n");
  const auto none = Make(s, Accel::kNone), bvh = Make(s, Accel::kBvh);
  EXPECT_EQ(bvh->BuildWork().bvhNodes, 3u) << "the root split into two leaves";
  for (const Tracer* t : {none.get(), bvh.get()}) {
    TraceStats stats;
    const PrimaryHit h = t->FirstHit({{0, 0, 0}, {0, 0, -1}}, stats);
    EXPECT_EQ(h.object, 0);
    EXPECT_EQ(h.t, 4.0);
    if (t == bvh.get()) {
      EXPECT_EQ(stats.nodeVisits, 3u);  // the root and both leaves: the tie crossed leaves
      EXPECT_EQ(stats.tests[int(ShapeKind::kSphere)], 3u);
      EXPECT_EQ(stats.tests[int(ShapeKind::kPolygon)], 1u);
    }
  }
  EXPECT_GT(ExpectSameImage(*none, *bvh), 0);
}

// Faces sharing an edge (ridges, valleys, flat, convex and concave, both windings) in one
// scene: the rays through the edge meet exactly one face, and the hierarchy the same one.
TEST(Bvh, PolygonsSharingEdgesGiveTheSameFace) {
  int cases = 0;
  for (const testing::SharedEdgeCase& c : testing::SharedEdgeCases()) {
    SCOPED_TRACE(c.name);
    Scene s = c.a;
    const int offset = int(s.materials.size());
    for (const Material& m : c.b.materials) s.materials.push_back(m);
    for (Primitive p : c.b.objects) {
      p.material += offset;
      s.objects.push_back(p);
    }
    if (s.lights.empty()) s.lights.push_back({.position = {0, 0, 0}});
    const auto none = Make(s, Accel::kNone, Precision::kDouble, 2),
               bvh = Make(s, Accel::kBvh, Precision::kDouble, 2);
    EXPECT_GT(ExpectSameImage(*none, *bvh), 0);
    ++cases;
  }
  EXPECT_GT(cases, 20);
}

// Ellipsoids (spheres under scale, rotation and shear), transformed cones and cylinders, a
// mirrored one, cones untransformed, a transformed cube and floor (the showcase generator).
TEST(Bvh, TransformedQuadricsAndConesGiveTheExhaustiveHits) {
  const Scene showcase = GenerateTransformedShowcase(64, 64);
  const std::string more =
      "f 0.8 0.6 0.3 0.7 0.3 20 0.4 1.3\n"
      "transform 1.4 0 0 -1.8  0 0.6 0 0.5  0 0 0.7 0.7\ns 0 0 -6 1\n"
      "transform 0.3 0 0 1  0 3 0 0  0 0 0.3 -2\ns 0 0 -8 1\n"
      "transform 0.7 0.7 0 0  -0.7 0.7 0 0  0 0.2 1 0\ns 1 -1 -7 0.8\n"
      "transform -1 0 0 0  0 1 0 0  0 0 1 0\ns 2 1 -9 1\n"
      "transform 1 0 0.5 0  0 1 0 0  0 0 1 0\nc\n-2 -1 -7 0.5\n-2 1 -7 0.5\n"
      "transform 0.5 0.2 0 0  0 1 0.3 0  0.1 0 2 0\nc\n0 -1 -4 0.6\n0 1 -4 0.1\n"
      "transform identity\nc\n2 -2 -8 1\n2 2 -8 0\nc\n-1 2 -6 0.3\n1 2 -6 0.3\n";
  const Scene mine = Nff("0 0 4", "0 0 -5", 50, 64, "l 3 6 4\nl -4 2 0\n" + more);
  for (const Scene* s : {&showcase, &mine}) {
    for (const Precision p : {Precision::kDouble, Precision::kFloat}) {
      const auto none = Make(*s, Accel::kNone, p), bvh = Make(*s, Accel::kBvh, p);
      EXPECT_GT(ExpectSameImage(*none, *bvh), 0);
      const Bounds box = SceneBox(*s);
      EXPECT_GT(ExpectSameRandomRays(*none, *bvh, box.lo, box.hi, 1000, 21).hits, 0);
    }
  }
}

// The Standard Procedural Databases' scenes beside the repository (ZEPHYR_SCENES or
// ../shared/scenes; skipped when absent), at 40×40: every pixel and random rays.
TEST(Bvh, EverySampleSceneGivesTheExhaustiveImage) {
  const char* env = std::getenv("ZEPHYR_SCENES");
  const std::filesystem::path dir = env ? env : "../shared/scenes";
  if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << "no sample scenes at " << dir;
  int run = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".nff") continue;
    SCOPED_TRACE(entry.path().string());
    Scene s = ReadNffFile(entry.path().string());
    s.camera.width = s.camera.height = 40;
    const auto none = Make(s, Accel::kNone, Precision::kDouble, 3),
               bvh = Make(s, Accel::kBvh, Precision::kDouble, 3);
    EXPECT_GT(ExpectSameImage(*none, *bvh), 0);
    const Bounds box = SceneBox(s);
    ExpectSameRandomRays(*none, *bvh, box.lo, box.hi, 300, 17);
    ++run;
  }
  EXPECT_GT(run, 0);
}

// Four unit spheres, opaque: objects 0 and 1 both at x = −10, 2 and 3 both at x = +10. The
// build, by hand: the root's box is 22 × 2 × 2 (half-area 22·2 + 2·2 + 2·22 = 92), each
// pair's 2 × 2 × 2 (12); the split between the pairs costs 2 + (12·2 + 12·2)/92 ≈ 2.5 < 4
// for a leaf of four, so the root splits; each pair's centroids coincide, so it is a leaf:
// 3 nodes made, 4 primitives binned (the root's; the leaves bin nothing). The walks:
//   * a ray down −z through (−10, 0): the root's box (1 box test) is entered, the root
//     visited (1 visit) and its two child boxes tested (2): the left entered, the right
//     (x ∈ [9, 11]) missed; the left leaf visited (2nd visit), its two spheres tested (2),
//     equal t, object 0 kept. 3 box tests, 2 visits, 2 sphere tests.
//   * a ray down −z through (0, 0): the root entered, visited, both children missed:
//     3 box tests, 1 visit, 0 tests.
//   * a ray down −z through (0, 5): the root's box (y ∈ [−1, 1]) missed: 1 box test, 0
//     visits.
//   * the shadow ray from (10, 0, 5) to the light at (10, 0, −5): as the first, mirrored,
//     but sphere 2, tested first and opaque, ends the walk: 3 box tests, 2 visits, 1 test,
//     product 0.
TEST(Bvh, NodeVisitsOfAHandBuiltSceneEqualTheHandCount) {
  const Scene s =
      Nff("0 0 10", "0 0 0", 40, 4,
          "l 10 0 -5\nf 1 1 1 1 0 0 0 1\ns -10 0 0 1\ns -10 0 0 1\ns 10 0 0 1\ns 10 0 0 1\n");
  const auto bvh = Make(s, Accel::kBvh);
  EXPECT_EQ(bvh->BuildWork().bvhNodes, 3u);
  EXPECT_EQ(bvh->BuildWork().bvhBinned, 4u);
  EXPECT_EQ(Make(s, Accel::kNone)->BuildWork().bvhNodes, 0u);
  struct Case {
    Vec3 origin;
    int object;
    uint64_t boxTests, visits, sphereTests;
  };
  for (const Case& c : {Case{{-10, 0, 10}, 0, 3, 2, 2}, Case{{0, 0, 10}, -1, 3, 1, 0},
                        Case{{0, 5, 10}, -1, 1, 0, 0}}) {
    TraceStats stats;
    EXPECT_EQ(bvh->FirstHit({c.origin, {0, 0, -1}}, stats).object, c.object);
    EXPECT_EQ(stats.boxTests, c.boxTests) << c.origin.x << " " << c.origin.y;
    EXPECT_EQ(stats.nodeVisits, c.visits) << c.origin.x << " " << c.origin.y;
    EXPECT_EQ(stats.tests[int(ShapeKind::kSphere)], c.sphereTests);
  }
  TraceStats shadow;
  EXPECT_EQ(bvh->LightThrough({10, 0, 5}, 0, 1e-9, shadow), 0.0);
  EXPECT_EQ(shadow.boxTests, 3u);
  EXPECT_EQ(shadow.nodeVisits, 2u);
  EXPECT_EQ(shadow.tests[int(ShapeKind::kSphere)], 1u);
  EXPECT_EQ(shadow.rays[int(RayKind::kShadow)], 1u);
}

// The walk visits the nearer child first and skips a child whose box the ray enters past the
// nearest hit found: two pairs of spheres on the z axis (at z = 0 and z = -10, one leaf each),
// rays along the axis from either side. From z = 10 down -z: the root and both children's
// boxes tested (3), the root and the z = 0 leaf visited (2), its two spheres tested, hit at
// t = 9; the z = -10 box is entered at t = 19 > 9, so never visited. From z = -20 up +z the
// mirror image: the z = -10 leaf first, object 2. Far-first would visit 3 nodes and test 4
// spheres in one of the two directions.
TEST(Bvh, TheNearerChildIsVisitedFirstAndAFartherBoxIsSkipped) {
  const Scene s =
      Nff("0 0 10", "0 0 0", 40, 4,
          "l 10 0 5\nf 1 1 1 1 0 0 0 1\ns 0 0 0 1\ns 0 0 0 1\ns 0 0 -10 1\ns 0 0 -10 1\n");
  const auto bvh = Make(s, Accel::kBvh);
  ASSERT_EQ(bvh->BuildWork().bvhNodes, 3u);
  struct Case {
    Vec3 origin, direction;
    int object;
  };
  for (const Case& c : {Case{{0, 0, 10}, {0, 0, -1}, 0}, Case{{0, 0, -20}, {0, 0, 1}, 2}}) {
    TraceStats stats;
    EXPECT_EQ(bvh->FirstHit({c.origin, c.direction}, stats).object, c.object) << c.origin.z;
    EXPECT_EQ(stats.boxTests, 3u) << c.origin.z;
    EXPECT_EQ(stats.nodeVisits, 2u) << c.origin.z;
    EXPECT_EQ(stats.tests[int(ShapeKind::kSphere)], 2u) << c.origin.z;
  }
}

TEST(Bvh, BuildKeepsEveryObjectOnceAndBoxesHoldTheirObjects) {
  const Scene s = GenerateRandomSpheres({.count = 1000, .seed = 2, .width = 8, .height = 8});
  std::vector<Bounds> boxes;
  for (const Primitive& p : s.objects) boxes.push_back(WorldBound(p));
  const double pad = 1e-6;
  const Bvh bvh = BuildBvh(boxes, pad);
  std::vector<int> seen(boxes.size(), 0);
  int leaves = 0;
  // Walk from the root: every leaf's objects inside its box, every child inside its parent.
  std::vector<int> stack = {0};
  while (!stack.empty()) {
    const BvhNodeT<double>& n = bvh.nodes[stack.back()];
    stack.pop_back();
    if (n.count > 0) {
      ++leaves;
      EXPECT_LE(n.count, kBvhMaxLeaf);
      for (int k = n.first; k < n.first + n.count; ++k) {
        ++seen[bvh.order[k]];
        for (int a = 0; a < 3; ++a) {
          EXPECT_LE(n.lo[a], boxes[bvh.order[k]].lo[a] - pad);
          EXPECT_GE(n.hi[a], boxes[bvh.order[k]].hi[a] + pad);
        }
      }
      continue;
    }
    for (int c : {n.first, n.first + 1}) {
      for (int a = 0; a < 3; ++a) {
        EXPECT_LE(n.lo[a], bvh.nodes[c].lo[a]);
        EXPECT_GE(n.hi[a], bvh.nodes[c].hi[a]);
      }
      stack.push_back(c);
    }
  }
  for (size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], 1) << "object " << i;
  EXPECT_GT(leaves, 1000 / kBvhMaxLeaf - 1);
  EXPECT_EQ(bvh.nodesBuilt, bvh.nodes.size());
  EXPECT_LE(bvh.depth, kBvhMaxDepth);
}

// The exact box of an ellipsoid touches it: the sphere of radius 2 under diag(1, 3, 0.5)
// then a rotation by 90° about z spans x ∈ ±6, y ∈ ±2, z ∈ ±1 about the mapped centre.
TEST(Bvh, WorldBoundOfAnEllipsoidIsItsExactBox) {
  Primitive p;
  p.shape = Sphere{{1, 0, 0}, 2};
  Affine a;
  a.m[0][0] = 0, a.m[0][1] = -3, a.m[0][2] = 0, a.m[0][3] = 5;
  a.m[1][0] = 1, a.m[1][1] = 0, a.m[1][2] = 0, a.m[1][3] = 0;
  a.m[2][0] = 0, a.m[2][1] = 0, a.m[2][2] = 0.5, a.m[2][3] = 0;
  p.transform = a;
  const Bounds b = WorldBound(p);  // centre: (5, 1, 0)
  EXPECT_DOUBLE_EQ(b.lo.x, -1);
  EXPECT_DOUBLE_EQ(b.hi.x, 11);
  EXPECT_DOUBLE_EQ(b.lo.y, -1);
  EXPECT_DOUBLE_EQ(b.hi.y, 3);
  EXPECT_DOUBLE_EQ(b.lo.z, -1);
  EXPECT_DOUBLE_EQ(b.hi.z, 1);
}

// The render command's PNGs: --accel bvh against --accel none, byte for byte, for seq, simd
// (host shading of the matrix; the recompute of uncertain pixels), dist and hetero (under
// mpirun: the children build their own hierarchy from the set-up message) and array (the
// host's rays of the all-rays-on-the-array method), on generated scenes.
TEST(Bvh, PngsOfEveryHostMethodAreByteEqualToTheExhaustive) {
  testing::TempDir dir;
  const std::string spheres = dir / "spheres.nff", flake = dir / "flake.nff";
  ASSERT_EQ(
      testing::RunZephyrProcess("gen spheres --count 40 --seed 5 --size 40x32 --out " + spheres)
          .status,
      0);
  ASSERT_EQ(testing::RunZephyrProcess("gen flake --depth 1 --size 32x32 --out " + flake).status, 0);
  for (const std::string& scene : {spheres, flake})
    for (const std::string method : {"seq", "simd", "dist", "hetero", "array"}) {
      std::string png[2];
      for (int i = 0; i < 2; ++i) {
        const std::string accel = i == 0 ? "none" : "bvh";
        png[i] = dir / (method + "-" + accel + ".png");
        const std::string args = "render --no-progress --method " + method + " " + scene +
                                 " --accel " + accel + " --out " + png[i] +
                                 (method == "dist" || method == "hetero" ? " --frame 16" : "");
        const testing::Launch r = method == "dist" || method == "hetero"
                                      ? testing::RunMpi(3, args)
                                      : testing::RunZephyrProcess(args);
        ASSERT_EQ(r.status, 0) << args << "\n" << r.output;
      }
      const std::string a = testing::ReadFile(png[0]), b = testing::ReadFile(png[1]);
      EXPECT_FALSE(a.empty());
      EXPECT_EQ(a, b) << method << " on " << scene;
    }
}

TEST(Bvh, AMalformedAccelIsRefusedWithTheNames) {
  testing::TempDir dir;
  const std::string spheres = dir / "s.nff";
  ASSERT_EQ(testing::RunZephyrProcess("gen spheres --count 3 --seed 1 --size 8x8 --out " + spheres)
                .status,
            0);
  const testing::Launch r = testing::RunZephyrProcess("render --no-progress --method seq " +
                                                      spheres + " --accel kd-tree");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("--accel: expected none or bvh, got 'kd-tree'"), std::string::npos)
      << r.output;
}

}  // namespace
}  // namespace zephyr
