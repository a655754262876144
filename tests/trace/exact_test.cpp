// The exact (128-bit) first-hit reference (hosts/trace/exact.h): known roots, and agreement
// with the double tracer on the object wherever the double hit is not close to a tie.
#include "hosts/trace/exact.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "hosts/scene/gen.h"

namespace zephyr {
namespace {

TEST(TraceExact, SphereRootsAreExactAndRespectTMin) {
  using exact::Real;
  // The unit sphere at z = 5 from the origin along +z: roots 4 and 6 exactly.
  const exact::RealVec c{0, 0, 5}, o{0, 0, 0}, d{0, 0, 1};
  EXPECT_EQ(*exact::SphereHit(c, Real(1), o, d, Real(0)), Real(4));
  EXPECT_EQ(*exact::SphereHit(c, Real(1), o, d, Real(4)), Real(6));  // t > tMin, strictly
  EXPECT_FALSE(exact::SphereHit(c, Real(1), o, d, Real(6)).has_value());
  // A direction of length 2 halves t; a ray one radius off the axis grazes (one root).
  EXPECT_EQ(*exact::SphereHit(c, Real(1), o, {0, 0, 2}, Real(0)), Real(2));
  EXPECT_EQ(*exact::SphereHit(c, Real(1), {1, 0, 0}, d, Real(0)), Real(5));
  EXPECT_FALSE(exact::SphereHit(c, Real(1), {Real(1) + Real(1e-30), 0, 0}, d, Real(0)).has_value());
}

TEST(TraceExact, FirstObjectAgreesWithTheDoubleTracerOnEveryKind) {
  for (const Scene& scene :
       {GenerateRandomSpheres({.count = 24, .seed = 4, .width = 32, .height = 32}),
        GenerateTransformedShowcase(32, 32)}) {
    TraceOptions o;
    o.depth = 1;
    const auto tracer = Tracer::Create(scene, o);
    TraceStats stats;
    const double tMin = std::max(scene.camera.hither, 0.0);
    int hits = 0;
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) {
        const PrimaryRay ray = tracer->Rays().At(x, y);
        const exact::Hit e = exact::FirstHit(scene, ray, tMin);
        const PrimaryHit h = tracer->FirstHit(ray, stats);
        ASSERT_EQ(e.object, h.object) << scene.source << " pixel " << x << "," << y;
        if (e.object < 0) continue;
        ++hits;
        EXPECT_NEAR(double(e.t), h.t, 1e-9 * std::max(1.0, h.t)) << x << "," << y;
      }
    EXPECT_GT(hits, 32 * 32 / 8) << scene.source;
  }
}

// A hither that cuts through a transformed sphere (an ellipsoid): a root is compared with tMin
// in world units (its object-space t scaled by the transformed direction's length), so the
// tracer's first hits still agree with the exact reference's where the hither lies among the
// ellipsoid's front hits.
TEST(TraceExact, AHitherThroughAnEllipsoidCutsItWhereTheExactReferenceDoes) {
  Scene scene = GenerateTransformedShowcase(48, 48);
  int ellipsoid = -1;
  for (size_t i = 0; i < scene.objects.size(); ++i)
    if (scene.objects[i].Kind() == ShapeKind::kSphere && scene.objects[i].transform)
      ellipsoid = int(i);
  ASSERT_GE(ellipsoid, 0) << "the showcase has an ellipsoid";
  std::vector<double> front, frontAt(48 * 48, -1);
  {
    const PrimaryRays rays(scene.camera);
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 48; ++x) {
        const exact::Hit e =
            exact::FirstHit(scene, rays.At(x, y), std::max(scene.camera.hither, 0.0));
        if (e.object == ellipsoid) front.push_back(frontAt[y * 48 + x] = double(e.t));
      }
  }
  ASSERT_GT(front.size(), 20u);
  std::sort(front.begin(), front.end());
  scene.camera.hither = front[front.size() / 2];  // half the front hits now lie before it
  TraceOptions o;
  o.depth = 1;
  const auto tracer = Tracer::Create(scene, o);
  TraceStats stats;
  int cut = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 48; ++x) {
      const PrimaryRay ray = tracer->Rays().At(x, y);
      const exact::Hit e = exact::FirstHit(scene, ray, scene.camera.hither);
      const PrimaryHit h = tracer->FirstHit(ray, stats);
      ASSERT_EQ(e.object, h.object) << "pixel " << x << "," << y;
      if (e.object >= 0) {
        EXPECT_NEAR(double(e.t), h.t, 1e-9 * std::max(1.0, h.t)) << x << "," << y;
      }
      // Its front cut away here: the hit is another surface, or the ellipsoid's far side.
      const double was = frontAt[y * 48 + x];
      cut += was >= 0 && (e.object != ellipsoid || double(e.t) != was);
    }
  EXPECT_GT(cut, 0) << "the hither should cut the ellipsoid's front";
}

}  // namespace
}  // namespace zephyr
