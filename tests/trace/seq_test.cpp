// Tests for the sequential tracer: primary rays, the intersection routines, shading rules,
// region rendering, the render command and its outputs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/methods/render.h"
#include "hosts/scene/gen.h"
#include "hosts/scene/nff.h"
#include "hosts/trace/image.h"
#include "hosts/trace/tracer.h"

namespace zephyr {
namespace {

Scene TinyScene(const std::string& objects, int w = 9, int h = 7,
                const std::string& from = "0 0 10") {
  return ParseNffOrThrow(
      "b 0.1 0.2 0.3\nv\nfrom " + from + "\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0\nresolution " +
          std::to_string(w) + " " + std::to_string(h) + "\nl 0 0 100\n" + objects,
      "tiny.nff");
}

TEST(TracePrimary, AngleSpansTopAndBottomPixelCentres) {
  const Scene s = TinyScene("", 9, 7);
  const PrimaryRays rays(s.camera);
  const PrimaryRay centre = rays.At(4, 3);
  EXPECT_NEAR(centre.direction.z, -1, 1e-15);
  const Vec3 top = rays.At(4, 0).direction, bottom = rays.At(4, 6).direction;
  EXPECT_NEAR(std::acos(Dot(top, bottom)) * 180 / M_PI, 40, 1e-9);
  EXPECT_GT(top.y, 0);                      // row 0 is the top
  EXPECT_GT(rays.At(8, 3).direction.x, 0);  // x grows to the right (from +z looking at -z, up +y)
  EXPECT_NEAR(Length(rays.At(0, 0).direction), 1, 1e-15);
}

TEST(TraceIntersect, SphereFormsAgreeNearAndDifferFarInFloat) {
  float roots[2];
  const Vec3T<float> o{0, 0, 0}, d{0, 0, -1};
  ASSERT_EQ(IntersectSphereHearnBaker<float>(o, d, {0, 0, -5}, 1, 0, roots), 2);
  EXPECT_FLOAT_EQ(roots[0], 4);
  EXPECT_FLOAT_EQ(roots[1], 6);
  ASSERT_EQ(IntersectSphereNaive<float>(o, d, {0, 0, -5}, 1, 0, roots), 2);
  EXPECT_FLOAT_EQ(roots[0], 4);
  // A unit sphere 1e5 away (Ray Tracing Gems ch. 7: beyond ~4096 r the radius stops
  // mattering in float). Offset 0.99 from the ray it is hit, offset 1.5 it is missed: the
  // Hearn–Baker form gets both right; the naive one computes |f|² − r² where r² is below
  // half an ulp of |f|², so it "hits" the sphere it should miss.
  EXPECT_EQ(IntersectSphereHearnBaker<float>(o, d, {0.99f, 0, -1e5f}, 1, 0, roots), 2);
  EXPECT_NEAR(roots[0], 1e5f - std::sqrt(1 - 0.99f * 0.99f), 0.02f);
  EXPECT_EQ(IntersectSphereHearnBaker<float>(o, d, {1.5f, 0, -1e5f}, 1, 0, roots), 0);
  EXPECT_EQ(IntersectSphereNaive<float>(o, d, {1.5f, 0, -1e5f}, 1, 0, roots), 2);
  double droots[2];
  EXPECT_EQ(IntersectSphereNaive<double>({0, 0, 0}, {0, 0, -1}, {1.5, 0, -1e5}, 1, 0, droots), 0);
}

TEST(TraceIntersect, TransformedPrimitivesAndConesAndPolygons) {
  const Scene s = TinyScene(
      "f 1 1 1 1 0 0 0 1\n"
      "transform 3 0 0 0  0 1 0 0  0 0 1 -5\ns 0 0 0 1\ntransform identity\n"  // ellipsoid, x
                                                                               // radius 3
      "c 0 -2 0 1 0 2 0 1\n"                                                   // cylinder along y
      "c 0 0 0 1 0 0 2 0\n"                                // cone along z, apex at z=2
      "p 6\n0 0 0\n4 0 0\n4 4 0\n2 1 0\n0 4 0\n0 2 0\n");  // concave (notched) hexagon
  // Ellipsoid: along x from x=10 at y=0,z=-5 the surface is at x=3.
  EXPECT_NEAR(*IntersectObject(s, 0, {10, 0, -5}, {-1, 0, 0}), 7, 1e-12);
  // Along y from y=10 the surface is at y=1; a non-unit direction gives t in its units.
  EXPECT_NEAR(*IntersectObject(s, 0, {0, 10, -5}, {0, -2, 0}), 4.5, 1e-12);
  EXPECT_FALSE(IntersectObject(s, 0, {0, 1.01, 10}, {0, 0, -1}));
  // Cylinder radius 1 around the y axis, open ends.
  EXPECT_NEAR(*IntersectObject(s, 1, {5, 0.5, 0}, {-1, 0, 0}), 4, 1e-12);
  EXPECT_FALSE(IntersectObject(s, 1, {5, 2.5, 0}, {-1, 0, 0}));         // beyond the end
  EXPECT_NEAR(*IntersectObject(s, 1, {0, 0, 0}, {0, 0, 1}), 1, 1e-12);  // from inside
  // Cone: radius 1 - z/2, so at z=1 the radius is 0.5.
  EXPECT_NEAR(*IntersectObject(s, 2, {5, 0, 1}, {-1, 0, 0}), 4.5, 1e-12);
  // Concave polygon: the notch (triangle (4,4) (2,1) (0,4)) is outside; (0.3, 3) and
  // (3.7, 3) beside it are inside.
  ASSERT_TRUE(IntersectObject(s, 3, {0.3, 3, 5}, {0, 0, -1}));
  EXPECT_NEAR(*IntersectObject(s, 3, {0.3, 3, 5}, {0, 0, -1}), 5, 1e-12);
  EXPECT_TRUE(IntersectObject(s, 3, {3.7, 3, 5}, {0, 0, -1}));
  EXPECT_FALSE(IntersectObject(s, 3, {2, 3, 5}, {0, 0, -1}));
  EXPECT_FALSE(IntersectObject(s, 3, {1, 3, 5}, {0, 0, -1}));
  EXPECT_FALSE(IntersectObject(s, 3, {5, 1, 5}, {0, 0, -1}));
}

// Issue 11: a transform's inverse is computed free of its scale, so a unit sphere written as
// a sphere of radius 1e120 shrunk by 1e-120 (or 1e-120 grown by 1e120) is traced as the
// unit sphere: their determinants (1e-360, 1e360) over- or underflow double.
TEST(TraceIntersect, TinyAndHugeTransformScalesTraceAsTheirWorldShape) {
  for (const auto& [e, r] :
       {std::pair<std::string, std::string>{"1e-120", "1e120"}, {"1e120", "1e-120"}}) {
    const std::string& k = e;
    const Scene s =
        TinyScene("f 1 1 1 1 0 0 0 1\ntransform " + e + " 0 0 0  0 " + e + " 0 0  0 0 " + e +
                  " -5\n"
                  "s 0 0 0 " +
                  r + "\n");
    ASSERT_TRUE(IntersectObject(s, 0, {0, 0, 10}, {0, 0, -1})) << k;
    EXPECT_NEAR(*IntersectObject(s, 0, {0, 0, 10}, {0, 0, -1}), 14, 1e-9) << k;
    EXPECT_NEAR(*IntersectObject(s, 0, {0, 0.5, 10}, {0, 0, -1}), 15 - std::sqrt(0.75), 1e-9) << k;
    EXPECT_FALSE(IntersectObject(s, 0, {0, 1.01, 10}, {0, 0, -1})) << k;
  }
}

// A floor lit from straight above, with a blocker between a floor point and the light.
double FloorBrightness(const std::string& blockerMaterial) {
  const Scene s = ParseNffOrThrow(
      "b 0 0 0\nv\nfrom 0 -10 10\nat 0 0 0\nup 0 0 1\nangle 30\nhither 0\nresolution 3 3\nl 0 0 "
      "20\n"
      "f 1 1 1 0.5 0 0 0 1\np 4\n-5 -5 0\n5 -5 0\n5 5 0\n-5 5 0\n" +
          blockerMaterial + "s 0 0 5 1\n",
      "shadow.nff");
  TraceOptions o;
  o.depth = 1;
  const auto tracer = Tracer::Create(s, o);
  TraceStats stats;
  PrimaryHit hit{0, Length(Vec3{0, -10, 10}), Normalize(Vec3{0, 10, -10})};
  return tracer->ShadeFromPrimaryHit(hit, stats).x;
}

TEST(TraceShade, TransparentBlockersAttenuateShadowsPerSurface) {
  const double open = FloorBrightness("f 1 1 1 1 0 0 0 1\n transform 1 0 0 100 0 1 0 0 0 0 1 0\n");
  // One light without a colour: intensity 1/2 and an ambient term 1/2 (docs/scene-format.md).
  // Ambient Kd · C · 1/2 = 0.25 (never shadowed); the light adds Kd · N·L · 1/2 = 0.25.
  EXPECT_NEAR(open, 0.25 + 0.25, 1e-12);
  EXPECT_NEAR(FloorBrightness("f 1 1 1 1 0 0 0 1\n"), 0.25, 1e-12);  // opaque
  EXPECT_NEAR(FloorBrightness("f 1 1 1 0 0 0 0.5 1.5\n"), 0.25 + 0.25 * 0.25,
              1e-12);  // two surfaces
}

TEST(TraceShade, RefractionAndTotalInternalReflection) {
  // The eye inside a glass sphere (ior 1.5): near-normal rays leave (refraction); a ray
  // meeting the surface at 64° > asin(1/1.5) = 41.8° is totally reflected.
  const Scene s = ParseNffOrThrow(
      "b 0 0 0\nv\nfrom 0 0 0.9\nat 1 0 0.9\nup 0 0 1\nangle 30\nhither 0\nresolution 3 3\nl 0 0 "
      "20\n"
      "f 1 1 1 0 0 0 1 1.5\ns 0 0 0 1\n",
      "glass.nff");
  TraceOptions o;
  o.depth = 2;
  const auto tracer = Tracer::Create(s, o);
  TraceStats grazing;
  const PrimaryHit tir = tracer->FirstHit({{0, 0, 0.9}, {1, 0, 0}}, grazing);
  ASSERT_EQ(tir.object, 0);
  tracer->ShadeFromPrimaryHit(tir, grazing);
  EXPECT_EQ(grazing.rays[int(RayKind::kRefracted)], 0u);
  EXPECT_EQ(grazing.rays[int(RayKind::kReflected)], 1u);
  TraceStats steep;
  const PrimaryHit out = tracer->FirstHit({{0, 0, 0.9}, {0, 0, 1}}, steep);
  tracer->ShadeFromPrimaryHit(out, steep);
  EXPECT_EQ(steep.rays[int(RayKind::kRefracted)], 1u);
  EXPECT_EQ(steep.rays[int(RayKind::kReflected)], 0u);
}

// Snell's law on the vectors: for incidence angles 0..89° in several planes and for four
// index ratios, the refracted direction is unit length, lies in the plane of d and n, goes
// across the surface (the normal's far side) on the same tangential side as d, and has
// sinθt = η·sinθi; past the critical angle asin(1/η) there is none (total internal
// reflection), on both sides of it to 1e-9 rad.
TEST(TraceShade, RefractObeysSnellsLawOnTheVectors) {
  const Vec3 n{0, 0, 1};
  int refracted = 0, reflected = 0;
  for (double eta : {1 / 1.5, 1 / 1.33, 1.0, 1.33, 1.5}) {
    for (int deg = 0; deg < 90; deg += 7)
      for (double phi : {0.0, 1.1, 2.5, 4.0}) {
        const double th = deg * M_PI / 180;
        const Vec3 d{std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi), -std::cos(th)};
        const std::optional<Vec3> t = Refract(d, n, eta);
        const std::string what = "eta " + std::to_string(eta) + " angle " + std::to_string(deg);
        if (eta * std::sin(th) > 1) {
          EXPECT_FALSE(t) << what;
          ++reflected;
          continue;
        }
        ASSERT_TRUE(t) << what;
        ++refracted;
        EXPECT_NEAR(Length(*t), 1, 1e-12) << what;
        EXPECT_LT(Dot(*t, n), 0) << what;                     // across the surface
        EXPECT_NEAR(Dot(*t, Cross(d, n)), 0, 1e-12) << what;  // in the plane of d, n
        const Vec3 tangentD = d - n * Dot(d, n), tangentT = *t - n * Dot(*t, n);
        EXPECT_GE(Dot(tangentT, tangentD), 0) << what;                     // not bent back
        EXPECT_NEAR(Length(tangentT), eta * std::sin(th), 1e-12) << what;  // sinθt = η·sinθi
        EXPECT_NEAR(-Dot(*t, n), std::sqrt(1 - eta * eta * std::sin(th) * std::sin(th)), 1e-12)
            << what;
      }
    if (eta > 1) {  // the critical angle
      const double critical = std::asin(1 / eta);
      for (double th : {critical - 1e-9, critical + 1e-9}) {
        const Vec3 d{std::sin(th), 0, -std::cos(th)};
        EXPECT_EQ(bool(Refract(d, n, eta)), th < critical) << eta << " at " << th;
      }
    }
  }
  EXPECT_GT(refracted, 0);
  EXPECT_GT(reflected, 0);
}

// The energy split at a glass pane (Kd 0, Ks 0.25, T 0.5, ior 1.5) in a scene with no light:
// a ray's colour is Ks·(what the reflected ray sees) + T·(what the refracted ray sees). A
// black sphere catches the reflected ray; the refracted one escapes to the background B.
// Entering, and leaving below the critical angle asin(1/1.5) = 41.81°: 0.5·B. Leaving past
// it, the T share goes the reflected way too: 0 with the sphere, (0.25 + 0.5)·B without.
TEST(TraceShade, RefractionAndTotalInternalReflectionSplitTheEnergy) {
  auto colour = [](double degrees, bool fromBelow, bool blocker, TraceStats& stats) {
    Scene s;
    s.source = "pane";
    s.background = {0.2, 0.4, 0.8};
    s.camera = Camera{{0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 40, 0, 3, 3};
    s.materials = {Material{{1, 1, 1}, 0, 0.25, 1, 0.5, 1.5}, Material{{1, 1, 1}, 0, 0, 0, 0, 1}};
    Primitive pane;
    pane.shape = Polygon{{{-10, -10, 0}, {10, -10, 0}, {10, 10, 0}, {-10, 10, 0}}, {}};
    s.objects.push_back(pane);
    const double th = degrees * M_PI / 180, z = fromBelow ? -1 : 1;
    const Vec3 o{0, 0, z}, d{std::sin(th), 0, -z * std::cos(th)};
    s.camera.from = o, s.camera.at = o + d, s.camera.up = {0, 1, 0};  // shading starts at the eye
    const Vec3 p = o + d * (1 / std::cos(th)), r{d.x, 0, -d.z};
    if (blocker) {
      Primitive ball;
      ball.shape = Sphere{p + r * 3.0, 1};
      ball.material = 1;
      s.objects.push_back(ball);
    }
    TraceOptions options;
    options.depth = 2;
    const auto tracer = Tracer::Create(s, options);
    const PrimaryHit hit = tracer->FirstHit({o, d}, stats);
    EXPECT_EQ(hit.object, 0);
    return tracer->ShadeFromPrimaryHit(hit, stats);
  };
  const Vec3 b{0.2, 0.4, 0.8};
  for (double deg : {0.0, 30.0, 41.7, 41.9, 60.0, 80.0}) {
    TraceStats in, out, outOpen;
    EXPECT_NEAR(Length(colour(deg, false, true, in) - b * 0.5), 0, 1e-12) << "entering at " << deg;
    EXPECT_EQ(in.rays[int(RayKind::kRefracted)], 1u) << deg;
    const bool tir = deg > 41.81;
    EXPECT_NEAR(Length(colour(deg, true, true, out) - b * (tir ? 0.0 : 0.5)), 0, 1e-12)
        << "leaving at " << deg;
    EXPECT_EQ(out.rays[int(RayKind::kRefracted)], tir ? 0u : 1u) << deg;
    EXPECT_EQ(out.rays[int(RayKind::kReflected)], tir ? 2u : 1u) << deg;
    EXPECT_NEAR(Length(colour(deg, true, false, outOpen) - b * 0.75), 0, 1e-12)
        << "leaving at " << deg;
  }
}

// A polygon's front is the side its vertices run counter-clockwise around, seen in its own
// coordinates; a mirroring transform reverses the winding in the world but not which side is
// the front (normals map by A⁻ᵀ). A glass pane (ior 1.5) met at 60° from its front is entered
// (refracted); from its back it would be left past the critical angle 41.8° (reflected).
TEST(TraceShade, AMirroringTransformKeepsAPolygonsFront) {
  for (const double mirror : {1.0, -1.0}) {
    Scene s;
    s.source = "pane";
    s.camera = Camera{{0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 40, 0, 3, 3};
    s.materials = {Material{{1, 1, 1}, 0, 0, 1, 1, 1.5}};
    Primitive pane;
    pane.shape = Polygon{{{-10, -10, 0}, {10, -10, 0}, {10, 10, 0}, {-10, 10, 0}}, {}};  // front +z
    pane.transform = Affine{};
    pane.transform->m[0][0] = mirror;
    s.objects.push_back(pane);
    const double th = 60 * M_PI / 180;
    const Vec3 o{0, 0, 1}, d{std::sin(th), 0, -std::cos(th)};
    s.camera.from = o, s.camera.at = o + d;
    for (const Precision p : {Precision::kFloat, Precision::kDouble}) {
      TraceOptions options;
      options.depth = 2;
      options.precision = p;
      const auto tracer = Tracer::Create(s, options);
      TraceStats stats;
      const PrimaryHit hit = tracer->FirstHit({o, d}, stats);
      ASSERT_EQ(hit.object, 0);
      tracer->ShadeFromPrimaryHit(hit, stats);
      EXPECT_EQ(stats.rays[int(RayKind::kRefracted)], 1u)
          << "x scaled by " << mirror << ", " << kPrecisionNames.NameOf(p);
      EXPECT_EQ(stats.rays[int(RayKind::kReflected)], 0u)
          << "x scaled by " << mirror << ", " << kPrecisionNames.NameOf(p);
    }
  }
}

// Issue 11: the shadow under a sphere resting on a floor: at pixel (35, 38) the floor is
// in shadow, so only the ambient term is left (SPD light rule: one light without a colour
// gives 1/2 and an ambient 1/2; Kd 0.8 · C 0.8 · 1/2 = 0.32). The floor's size must not
// matter: exporters write "infinite" floors as ±1e6 polygons (±1e9 in double).
Scene FloorAndSphere(const std::string& half) {
  return ParseNffOrThrow(
      "v\nfrom 0 3 8\nat 0 0.5 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 64 64\nb 0.1 0.1 "
      "0.3\nl 4 8 3\n"
      "f 0.8 0.8 0.8 0.8 0.2 20 0 0\np 4\n-" +
          half + " 0 -" + half + "\n" + half + " 0 -" + half + "\n" + half + " 0 " + half + "\n-" +
          half + " 0 " + half + "\nf 0.9 0.2 0.2 0.7 0.3 40 0 0\ns 0 1 0 1\n",
      "floor.nff");
}

TEST(TraceShade, ContactShadowDoesNotDependOnTheFloorsSize) {
  for (const Precision p : {Precision::kFloat, Precision::kDouble}) {
    for (const std::string half : {"4", "1e6", "1e9"}) {
      TraceOptions o;
      o.depth = 1;
      o.precision = p;
      const Scene s = FloorAndSphere(half);
      const auto tracer = Tracer::Create(s, o);
      TraceStats stats;
      PrimaryHit hit;
      const Vec3 c = tracer->TracePixel(35, 38, stats, &hit);
      ASSERT_EQ(hit.object, 0) << half;
      const double tol = p == Precision::kFloat ? 1e-6 : 1e-12;
      EXPECT_NEAR(c.x, 0.32, tol) << kPrecisionNames.NameOf(p) << " floor ±" << half;
      EXPECT_NEAR(c.y, 0.32, tol) << kPrecisionNames.NameOf(p) << " floor ±" << half;
    }
  }
}

// Issue 11: an object out of view changes nothing, however large (the offset secondary
// rays skip follows the hit, not the scene's extent).
TEST(TraceShade, AFarObjectOutOfViewLeavesTheImageAlone) {
  for (const Precision p : {Precision::kFloat, Precision::kDouble}) {
    TraceOptions o;
    o.precision = p;
    o.depth = 1;  // primary and shadow rays: neither can reach behind the eye
    const Scene near = FloorAndSphere("4");
    Scene far = near;
    Primitive big = far.objects[0];  // a 2e6 × 2e6 floor behind the eye, 1e6 away
    for (Vec3& v : std::get<Polygon>(big.shape).vertices) v = v * 250000.0 + Vec3{0, 0, 2e6};
    far.objects.push_back(big);
    Image a(64, 64), b(64, 64);
    TraceStats stats;
    RenderRegion(*Tracer::Create(near, o), 0, 0, 64, 64, a.pixels, stats);
    RenderRegion(*Tracer::Create(far, o), 0, 0, 64, 64, b.pixels, stats);
    EXPECT_EQ(a.pixels, b.pixels) << kPrecisionNames.NameOf(p);
  }
}

// Issue 11: two polygons sharing an edge leave no crack. The roof ridge seen edge-on: the
// rays of row 32 pass exactly through the shared edge and must show the roof.
TEST(TraceIntersect, ARayThroughASharedEdgeHitsOneOfTheFaces) {
  const Scene roof = ParseNffOrThrow(
      "v\nfrom 0 0 0\nat 0 0 -1\nup 0 1 0\nangle 40\nhither 0.01\nresolution 65 65\nb 1 0 1\nl 0 "
      "10 10\n"
      "l 0 -10 10\nf 0.9 0.8 0.2 0.9 0 1 0 0\np 4\n-3 0 -5\n3 0 -5\n3 2 -7\n-3 2 -7\n"
      "p 4\n-3 0 -5\n-3 -2 -7\n3 -2 -7\n3 0 -5\n",
      "roof.nff");
  for (const Precision p : {Precision::kFloat, Precision::kDouble}) {
    TraceOptions o;
    o.precision = p;
    const auto tracer = Tracer::Create(roof, o);
    TraceStats stats;
    for (int x = 0; x < 65; ++x) {
      const PrimaryRay ray = tracer->Rays().At(x, 32);
      ASSERT_EQ(ray.direction.y, 0);  // exactly through the ridge
      if (std::abs(ray.direction.x / ray.direction.z) * 5 >= 3) continue;  // beyond the roof's ends
      EXPECT_GE(tracer->FirstHit(ray, stats).object, 0) << kPrecisionNames.NameOf(p) << " x=" << x;
    }
  }
  // The whole kind: rays through many points of shared edges (and near them) hit exactly
  // one face of each pair, whatever the faces' winding: a folded pair, a flat pair split
  // on a diagonal, and a pair wound inconsistently.
  const Scene pairs = ParseNffOrThrow(
      "v\nfrom 0 0 0\nat 0 0 -1\nup 0 1 0\nangle 40\nhither 0\nresolution 3 3\nb 0 0 0\n"
      "f 1 1 1 1 0 0 0 0\n"
      "p 3\n-1.3 -0.7 -5.1\n1.1 0.3 -4.7\n0.2 1.9 -6.3\np 3\n-1.3 -0.7 -5.1\n0.4 -1.7 -3.9\n1.1 "
      "0.3 -4.7\n"
      "p 3\n-2 -1 -6\n2 -1 -6\n2 1 -6\np 3\n-2 -1 -6\n2 1 -6\n-2 1 -6\n"
      "p 3\n-0.9 0.1 -3.3\n0.7 0.6 -3.1\n0.1 1.4 -3.9\np 3\n-0.9 0.1 -3.3\n0.7 0.6 -3.1\n-0.2 -0.8 "
      "-2.7\n",
      "pairs.nff");
  const std::pair<Vec3, Vec3> edges[] = {{{-1.3, -0.7, -5.1}, {1.1, 0.3, -4.7}},
                                         {{-2, -1, -6}, {2, 1, -6}},
                                         {{-0.9, 0.1, -3.3}, {0.7, 0.6, -3.1}}};
  for (int pair = 0; pair < 3; ++pair) {
    const auto [a, b] = edges[pair];
    int rays = 0;
    for (int k = 1; k < 200; ++k) {
      for (const double nudge : {0.0, 1e-15, -1e-15, 1e-9, -1e-9}) {
        const Vec3 target = a + (b - a) * (k / 200.0) + Vec3{0, nudge, 0};
        const Vec3 d = Normalize(target);
        int hits = 0;
        for (int i = 2 * pair; i < 2 * pair + 2; ++i)
          hits += IntersectObject(pairs, i, {0, 0, 0}, d).has_value();
        EXPECT_EQ(hits, 1) << "pair " << pair << " k " << k << " nudge " << nudge;
        ++rays;
      }
    }
    EXPECT_EQ(rays, 199 * 5);
  }
}

// Issue 11: a scene at a scale of 1e140 renders like the same scene at scale 1 (no square
// overflows in double), and a scale float cannot square is a clear error naming the line.
TEST(TraceRender, LargeScenesRenderOrAreAClearError) {
  auto scene = [](const std::string& k) {
    return ParseNffOrThrow("v\nfrom 0 0 10" + k +
                               "\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0\nresolution 9 9\n"
                               "b 0.1 0.2 0.3\nl 3" +
                               k + " 4" + k + " 10" + k +
                               " 1 1 1\nf 1 0.5 0 0.8 0.2 10 0 0\n"
                               "s 0 0 0 1" +
                               k + "\ns 0 0 0.8" + k + " 0.3" + k + "\n",
                           "big.nff");
  };
  const Scene unit = scene(""), big = scene("e140");
  Image a(9, 9), b(9, 9);
  TraceStats stats;
  RenderRegion(*Tracer::Create(unit, {}), 0, 0, 9, 9, a.pixels, stats);
  RenderRegion(*Tracer::Create(big, {}), 0, 0, 9, 9, b.pixels, stats);
  EXPECT_GT(Psnr(a, b), 60);
  EXPECT_NE(b.pixels[4 * 9 + 4], big.background);
  TraceOptions f;
  f.precision = Precision::kFloat;
  try {
    Tracer::Create(scene("e18"), f);
    FAIL() << "expected a UserError";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("big.nff:2:1: the eye ('from') reaches 1e+19"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("--precision double"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(Tracer::Create(scene("e15"), f));
}

// Issue 11: lights without a colour (SPD scenes) are √N/(2N) each with an ambient term of
// the same, in every method's shading: a lit point and a shadowed one, by value.
TEST(TraceShade, LightsWithoutColourFollowTheSpdRule) {
  const Scene s = ParseNffOrThrow(
      "v\nfrom 0 -10 10\nat 0 0 0\nup 0 0 1\nangle 30\nhither 0\nresolution 3 3\nb 0 0 0\n"
      "l 0 0 20\nl 0 0 30\nl 0 0 40\nl 0 0 50\nf 1 0.5 0.25 0.5 0 0 0 0\np 4\n-5 -5 0\n5 -5 0\n5 5 "
      "0\n-5 5 0\n",
      "spd.nff");
  TraceOptions o;
  o.depth = 1;
  const auto tracer = Tracer::Create(s, o);
  TraceStats stats;
  const PrimaryHit hit{0, Length(Vec3{0, -10, 10}), Normalize(Vec3{0, 10, -10})};
  // N = 4: each light 2/8 = 0.25, N·L = 1 for all four; ambient 0.25.
  const Vec3 c = tracer->ShadeFromPrimaryHit(hit, stats);
  EXPECT_NEAR(c.x, 0.5 * 1 * (4 * 0.25 + 0.25), 1e-12);
  EXPECT_NEAR(c.y, 0.5 * 0.5 * (4 * 0.25 + 0.25), 1e-12);
  EXPECT_NEAR(c.z, 0.5 * 0.25 * (4 * 0.25 + 0.25), 1e-12);
}

TEST(TraceRender, RegionsAreBitIdenticalToTheFullImage) {
  const Scene s = GenerateRandomSpheres({12, 5, 40, 32});
  const auto tracer = Tracer::Create(s, {});
  TraceStats full, part;
  std::vector<Vec3> all, frame;
  std::vector<PrimaryHit> allHits, frameHits;
  RenderRegion(*tracer, 0, 0, 40, 32, all, full, &allHits);
  RenderRegion(*tracer, 13, 9, 16, 8, frame, part, &frameHits);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 16; ++x) {
      const size_t i = size_t(y + 9) * 40 + (x + 13), j = size_t(y) * 16 + x;
      EXPECT_EQ(all[i], frame[j]);
      EXPECT_EQ(allHits[i].object, frameHits[j].object);
      EXPECT_EQ(allHits[i].t, frameHits[j].t);
    }
  }
  EXPECT_EQ(part.rays[int(RayKind::kPrimary)], 16u * 8);
  // Exhaustive: every ray of every kind (primary, shadow, reflected, refracted) tests every
  // object, so each kind's test count is its object count times all the rays traced.
  uint64_t rays = 0, objects[kShapeKinds] = {};
  for (uint64_t r : full.rays) rays += r;
  for (const Primitive& p : s.objects) ++objects[int(p.Kind())];
  EXPECT_GT(full.rays[int(RayKind::kShadow)], 0u);
  for (int k = 0; k < kShapeKinds; ++k) EXPECT_EQ(full.tests[k], objects[k] * rays) << k;
}

TEST(TraceRender, FloatAndDoubleAgreeOnAnImage) {
  const Scene s = GenerateSphereflake(1, 48, 48);
  TraceOptions d, f;
  f.precision = Precision::kFloat;
  Image a(48, 48), b(48, 48);
  TraceStats stats;
  RenderRegion(*Tracer::Create(s, d), 0, 0, 48, 48, a.pixels, stats);
  RenderRegion(*Tracer::Create(s, f), 0, 0, 48, 48, b.pixels, stats);
  EXPECT_GT(Psnr(a, b), 35);
  bool differ = false;  // the float tracer really computes in float
  for (size_t i = 0; i < a.pixels.size(); ++i) differ |= a.pixels[i] != b.pixels[i];
  EXPECT_TRUE(differ);
}

TEST(TraceRender, CommandWritesPngReportAndPrimaryCsv) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("zephyr_trace_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string scene = (dir / "s.nff").string(), png = (dir / "s.png").string(),
                    json = (dir / "s.json").string(), csv = (dir / "s.csv").string();
  const char* gen[] = {"zephyr", "gen",    "spheres", "--count", "6",          "--seed",
                       "2",      "--size", "20x10",   "--out",   scene.c_str()};
  ASSERT_EQ(RunZephyr(11, gen), 0);
  const char* render[] = {"zephyr",         "render",    "--method",  "seq",      "--scene",
                          scene.c_str(),    "--out",     png.c_str(), "--report", json.c_str(),
                          "--dump-primary", csv.c_str(), "--depth",   "3"};
  ASSERT_EQ(RunZephyr(14, render), 0);
  const Image img = ReadPng(png);
  EXPECT_EQ(img.width, 20);
  EXPECT_EQ(img.height, 10);
  std::ifstream jf(json);
  const auto report = nlohmann::json::parse(jf);
  EXPECT_EQ(report["rays"]["primary"], 200);
  EXPECT_EQ(report["options"]["depth"], 3);
  EXPECT_TRUE(report["phases"]["render"].is_number());
  std::ifstream cf(csv);
  std::string line;
  std::getline(cf, line);
  EXPECT_EQ(line, "x,y,dx,dy,dz,object,t,flags");
  const Scene s = ReadNffFile(scene);
  const auto tracer = Tracer::Create(s, {});
  int rows = 0;
  while (std::getline(cf, line)) {
    int x, y, object;
    double dx, dy, dz, t;
    unsigned flags;
    ASSERT_EQ(std::sscanf(line.c_str(), "%d,%d,%lf,%lf,%lf,%d,%lf,%u", &x, &y, &dx, &dy, &dz,
                          &object, &t, &flags),
              8);
    EXPECT_EQ(x, rows % 20);
    EXPECT_EQ(y, rows / 20);
    const PrimaryRay ray = tracer->Rays().At(x, y);
    EXPECT_EQ(dx, ray.direction.x);  // %.17g round-trips exactly
    TraceStats stats;
    const PrimaryHit hit = tracer->FirstHit(ray, stats);
    EXPECT_EQ(object, hit.object);
    if (object >= 0) {
      EXPECT_EQ(t, hit.t);
    }
    EXPECT_EQ(flags, 0u);
    ++rows;
  }
  EXPECT_EQ(rows, 200);
  const char* bad[] = {"zephyr", "render", "--scene", "/nonexistent.nff"};
  EXPECT_NE(RunZephyr(4, bad), 0);
  const char* badMethod[] = {"zephyr", "render", "--method", "nope", "--scene", scene.c_str()};
  EXPECT_NE(RunZephyr(6, badMethod), 0);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace zephyr
