// Adversarial soundness cases for the SIMD pass's bounds (docs/simd.md, "Error bounds",
// "Uncertain pixels", "Refine pass"): views made of the situations the bounds are weakest in
// — a fan of rays across a sphere's silhouette, spheres that cut through each other (a tie
// along their intersection curve), cones and cylinders seen along and across their axis,
// polygon seams and polygons drawn twice in one plane. At several widths and with `keep`,
// no pixel whose first object differs from the exact reference (hosts/trace/exact.h) may be
// unflagged; with `refine`, no pixel may differ after repair.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "hosts/scene/nff.h"
#include "hosts/simd/pass.h"
#include "hosts/trace/exact.h"

namespace zephyr::simd {
namespace {

constexpr const char* kHeader =
    "b 0 0 0\nv\nfrom {}\nat {}\nup 0 1 0\nangle {}\nhither 0.01\nresolution 32 32\n"
    "l 5 5 5\nf 1 0.5 0.2 0.7 0.3 10 0 1\n";

Scene Build(const std::string& from, const std::string& at, double angle, const std::string& body) {
  std::string head = kHeader;
  auto put = [&](const std::string& v) { head.replace(head.find("{}"), 2, v); };
  put(from), put(at), put(std::to_string(angle));
  return ParseNffOrThrow(head + body, "adversarial test");
}

std::vector<int> ExactObjects(const Scene& scene) {
  const PrimaryRays rays(scene.camera);
  const std::vector<int> planes = exact::CoplanarPolygons(scene);
  std::vector<int> out;
  for (int y = 0; y < scene.camera.height; ++y)
    for (int x = 0; x < scene.camera.width; ++x)
      out.push_back(
          exact::FirstHit(scene, rays.At(x, y), std::max(scene.camera.hither, 0.0), planes).object);
  return out;
}

// At each width (-1: planned): with `keep`, every pixel whose object differs is flagged; with
// `refine`, every pixel agrees after repair. Returns the planned width's `keep` pass.
PrimaryPass ExpectSound(const Scene& scene, std::initializer_list<int> widths) {
  const std::vector<int> want = ExactObjects(scene);
  PrimaryPass planned;
  for (int bits : widths) {
    SimdOptions o;
    o.formats.fracBits = bits;
    o.uncertain = UncertainPolicy::kKeep;
    PrimaryPass kept = RunPrimaryPass(scene, o);
    int wrong = 0, unflaggedWrong = 0;
    for (size_t i = 0; i < want.size(); ++i)
      if (kept.matrix.hits[i].object != want[i])
        ++wrong, unflaggedWrong += kept.matrix.flags[i] == 0;
    EXPECT_EQ(unflaggedWrong, 0) << bits << " fraction bits, " << wrong << " wrong";
    o.uncertain = UncertainPolicy::kRefine;
    const PrimaryPass refined = RunPrimaryPass(scene, o);
    int after = 0;
    for (size_t i = 0; i < want.size(); ++i) after += refined.matrix.hits[i].object != want[i];
    EXPECT_EQ(after, 0) << bits << " fraction bits, after refine and repair";
    if (bits < 0) planned = std::move(kept);
  }
  return planned;
}

// Every listed object is the first hit of some pixel (else the case would prove little).
void ExpectSeen(const Scene& scene, std::initializer_list<int> objects) {
  const std::vector<int> want = ExactObjects(scene);
  for (int k : objects)
    EXPECT_NE(std::find(want.begin(), want.end(), k), want.end()) << "object " << k;
}

TEST(SimdAdversarial, GrazingFanAcrossASphereSilhouette) {
  // A 2° view centred on the silhouette of a unit sphere, a second sphere behind it.
  const Scene s = Build("0 0 0", "1 0 -10", 2, "s 0 0 -10 1\ns 1.2 0 -14 1\n");
  ExpectSeen(s, {0, 1});
  ExpectSound(s, {5, 8, 12, -1});
}

TEST(SimdAdversarial, NearTiesOfSpheresCuttingEachOther) {
  // Two spheres cutting each other (their t are equal along the intersection curve), and a
  // pair whose surfaces are 1e-5 apart.
  const Scene s = Build("0 0 0", "0 0 -5", 30,
                        "s -0.5 0 -5 1\ns 0.5 0 -5 1\ns 0 1.6 -6 0.5\ns 0 1.6 -6.00001 0.5\n");
  ExpectSeen(s, {0, 1, 2});
  ExpectSound(s, {5, 8, 12, 16, -1});
}

TEST(SimdAdversarial, ConesAlongAndAcrossTheirAxis) {
  // A tube seen end-on (the eye on its axis), a cone whose axis crosses the view, and a
  // cylinder seen nearly along its axis, over a floor.
  const Scene s = Build("0 0 0", "0 0 -10", 40,
                        "c 0 0 -6 0.8 0 0 -12 0.8\n"
                        "c -2 -2 -8 0.9 2 -2 -8 0\n"
                        "c 1.5 1.5 -5 0.4 1.7 1.6 -11 0.4\n"
                        "p 4\n-9 -4 -2\n9 -4 -2\n9 -4 -20\n-9 -4 -20\n");
  ExpectSeen(s, {0, 1, 2});
  ExpectSound(s, {8, 12, -1});
}

TEST(SimdAdversarial, CylindersJoinedBySpheresAndSeenEndOn) {
  // The joints of SPD rings and lattice: cylinders ending in spheres of their own radius (the
  // rim circle lies on the sphere, so the surfaces tie along it; a rim within its height
  // margin), a cylinder pointing almost at the eye (its divisor |A| small over its whole
  // image: the per-PE ladder and the far root hidden by a certain near one) and an open tube
  // seen obliquely through its end (the far root, its inside wall, visible).
  const Scene s = Build("0 0 0", "0 0 -6", 40,
                        "c -1 0 -6 0.3 1 0 -6 0.3\ns -1 0 -6 0.3\ns 1 0 -6 0.3\n"
                        "c 1 0 -6 0.3 1.3 1.2 -7 0.3\ns 1.3 1.2 -7 0.3\n"
                        "c -1.5 1.5 -5 0.25 -1.42 1.46 -9 0.25\n"
                        "c 0.4 -1.3 -4.5 0.4 0.9 -1.5 -7.5 0.4\n"
                        "p 4\n-9 -3 -2\n9 -3 -2\n9 -3 -20\n-9 -3 -20\n");
  ExpectSeen(s, {0, 1, 2, 3, 5, 6});
  ExpectSound(s, {8, 12, 16, -1});
}

// A quad drawn twice (two triangulations) in a tilted plane.
const std::string kTwiceDrawnQuad =
    "pp 3\n-2 -1 -6 0 0 1\n0 -1 -7 0 0 1\n0 1 -7 0 0 1\n"
    "pp 3\n0 1 -7 0 0 1\n-2 1 -6 0 0 1\n-2 -1 -6 0 0 1\n"
    "p 3\n-2 -1 -6\n0 -1 -7\n-2 1 -6\n"
    "p 3\n0 -1 -7\n0 1 -7\n-2 1 -6\n";

// The quad above, a fan of triangles around a vertex (seams where they share edges), and a
// polygon seen nearly edge-on.
const std::string kPolygons = kTwiceDrawnQuad +
                              "p 3\n1 0 -6\n2 -1 -6.5\n2.2 0.4 -6.2\n"
                              "p 3\n1 0 -6\n2.2 0.4 -6.2\n1.6 1.3 -5.8\n"
                              "p 3\n1 0 -6\n1.6 1.3 -5.8\n0.6 0.9 -6.1\n"
                              "p 4\n0.2 -2.5 -4\n2 -2.5 -4\n2 -2.501 -9\n0.2 -2.501 -9\n";

TEST(SimdAdversarial, PolygonSeamsAndPolygonsDrawnTwice) {
  const Scene s = Build("0 0 0", "0 -0.3 -6", 50, kPolygons);
  ExpectSeen(s, {0, 1, 4, 5, 6, 7});
  ExpectSound(s, {6, 10, -1});
}

TEST(SimdAdversarial, PolygonsInOnePlaneAreNoNearTie) {
  // The twice-drawn quad alone: its two triangulations have the same t bit for bit, and the
  // lowest index is first, as in the exact reference; no pixel is a near tie.
  const Scene s = Build("0 0 0", "-1 0 -6.5", 40, kTwiceDrawnQuad);
  const std::vector<int> planes = exact::CoplanarPolygons(s);
  EXPECT_EQ(planes, (std::vector<int>{0, 0, 0, 0}));
  const PrimaryPass planned = ExpectSound(s, {8, -1});
  EXPECT_EQ(planned.plan.planeClasses, 1);
  EXPECT_EQ(planned.uncertain.nearTie, 0);
  int onQuad = 0;
  for (const PrimaryHit& h : planned.matrix.hits) onQuad += h.object >= 0;
  EXPECT_GT(onQuad, 150);
}

TEST(SimdAdversarial, CoplanarPolygonsAreDecidedExactly) {
  // The same triangle moved off its plane by one ulp of a coordinate is another plane.
  const Scene s = Build("0 0 0", "0 0 -6", 40,
                        "p 3\n-2 -1 -6\n0 -1 -7\n0 1 -7\n"
                        "p 3\n-2 -1 -6\n0 -1 -7\n0 1 -7.000000000000001\n"
                        "p 3\n0 1 -7\n-2 1 -6\n-2 -1 -6\n"
                        "s 5 5 5 1\n");
  EXPECT_EQ(exact::CoplanarPolygons(s), (std::vector<int>{0, 1, 0, -1}));
}

}  // namespace
}  // namespace zephyr::simd
