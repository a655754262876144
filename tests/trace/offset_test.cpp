// The secondary-ray offset (docs/shading.md, "The colour at a hit"): secondary and shadow rays
// skip relative · (gain · (|o|∞ + t) + the object's own magnitude), and each term must bound
// the rounding of what the tracer computes. Checked against each magnitude:
// one scene (a floor, a sphere resting on it, a mirror sphere) seen near, with the eye far
// away (t), moved far from the world origin (the ray's origin), and with far numbers in its
// objects (a huge floor; object spaces far from the world), in float and double, where the
// contact shadow and the reflections must come out as a hand computation in double says; and
// for every primitive kind, a surface whose own numbers are far from the hit but that has no
// occluder is never shadowed by itself.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "hosts/scene/nff.h"
#include "hosts/trace/tracer.h"

namespace zephyr {
namespace {

// ---- The scene in its own frame, traced by hand in double ------------------------------------

// Floor y = 0, |x|, |z| <= 4; a red sphere resting on it; a mirror sphere resting on it.
constexpr double kFloorHalf = 4;
const Vec3 kRedCentre{0, 1, 0}, kMirrorCentre{2.2, 0.6, 0.8};
constexpr double kRedRadius = 1, kMirrorRadius = 0.6;
const Vec3 kLight{4, 8, 3}, kEye{0, 3, 8}, kBackground{0.1, 0.1, 0.3};
const Material kFloorMaterial{{0.8, 0.8, 0.8}, 0.8, 0, 0, 0, 1};
const Material kRedMaterial{{0.9, 0.2, 0.2}, 0.9, 0, 0, 0, 1};
const Material kMirrorMaterial{{1, 1, 1}, 0.2, 0.7, 50, 0, 1};
enum Object { kFloor = 0, kRed = 1, kMirror = 2 };

struct LocalHit {
  int object = -1;
  double t = 0;
  Vec3 point, normal;  // normal: outward (the floor's +y)
};

// The nearest hit along o + t d (d unit) beyond tMin, skipping `skip`; `margin` becomes the
// smallest distance of the ray from a silhouette or floor edge it passes (so a probe whose
// rays pass within rounding of one can be left out).
LocalHit TraceLocal(const Vec3& o, const Vec3& d, double tMin, int skip, double& margin) {
  LocalHit best;
  best.t = INFINITY;
  for (const int k : {kRed, kMirror}) {
    if (k == skip) continue;
    const Vec3 c = k == kRed ? kRedCentre : kMirrorCentre;
    const double r = k == kRed ? kRedRadius : kMirrorRadius;
    const double b = Dot(c - o, d);
    if (b <= 0) continue;  // the sphere is behind
    const double closest = Length(c - o - d * b);
    margin = std::min(margin, std::abs(closest - r));
    if (closest >= r) continue;
    const double t = b - std::sqrt(r * r - closest * closest);
    if (t > tMin && t < best.t) best = {k, t, o + d * t, (o + d * t - c) / r};
  }
  // The floor plane: a hit inside the square, or, outside it, one that a larger floor would
  // give (so a probe whose ray meets the plane there is left out: margin 0).
  if (skip != kFloor && d.y != 0) {
    const double t = -o.y / d.y;
    if (t > tMin && t < best.t) {
      const Vec3 p = o + d * t;
      const double edge = kFloorHalf - std::max(std::abs(p.x), std::abs(p.z));
      margin = std::min(margin, edge > 0 ? edge : 0.0);
      if (edge > 0) best = {kFloor, t, p, {0, 1, 0}};
    }
  }
  return best;
}

const Material& MaterialOf(int object) {
  return object == kFloor ? kFloorMaterial : object == kRed ? kRedMaterial : kMirrorMaterial;
}

// docs/shading.md's colour at a hit seen along d with one white light and no ambient term,
// reflections to `depth` levels; nullopt when a ray of the tree passes within 0.02 of an
// edge, a shadow edge or a terminator, or meets its occluder within 0.5 (beyond any offset
// below), where two correct computations may differ.
std::optional<Vec3> ShadeLocal(const LocalHit& h, const Vec3& d, int depth) {
  const Material& m = MaterialOf(h.object);
  const Vec3 n = Dot(h.normal, d) < 0 ? h.normal : -h.normal;
  const Vec3 toLight = Normalize(kLight - h.point);
  const double nl = Dot(n, toLight);
  if (std::abs(nl) < 0.05) return std::nullopt;
  Vec3 colour;
  if (nl > 0) {
    double margin = INFINITY;
    const LocalHit blocker = TraceLocal(h.point, toLight, 0, h.object, margin);
    if (margin < 0.02 || (blocker.object >= 0 && blocker.t < 0.5)) return std::nullopt;
    if (blocker.object < 0) {
      colour += Mul(m.colour, Vec3{1, 1, 1}) * (m.kd * nl);
      if (m.ks > 0) {
        const double rv = -Dot(n * (2 * nl) - toLight, d);
        if (rv > 0) colour += Vec3{1, 1, 1} * (m.ks * std::pow(rv, m.shine));
      }
    }
  }
  if (depth > 1 && m.ks > 0) {
    const Vec3 r = d - n * (2 * Dot(d, n));
    double margin = INFINITY;
    const LocalHit next = TraceLocal(h.point, r, 0, h.object, margin);
    if (margin < 0.02 || (next.object >= 0 && next.t < 0.5)) return std::nullopt;
    if (next.object < 0) {
      colour += kBackground * m.ks;
    } else {
      const std::optional<Vec3> seen = ShadeLocal(next, r, depth - 1);
      if (!seen) return std::nullopt;
      colour += *seen * m.ks;
    }
  }
  return colour;
}

// A point of the scene seen from kEye, with its colour by hand.
struct Probe {
  Vec3 point, direction;  // direction: unit, from kEye
  int object;
  Vec3 colour;
  bool shadowed;  // the light is in front of the surface and blocked (the contact shadow)
};

std::vector<Probe> Probes() {
  std::vector<Vec3> points;
  for (double x = -3.5; x <= 3.5; x += 0.125)
    for (double z = -3.5; z <= 3.5; z += 0.125) points.push_back({x, 0, z});
  for (const auto& [c, r] :
       {std::pair{kRedCentre, kRedRadius}, std::pair{kMirrorCentre, kMirrorRadius}})
    for (double theta = 0.05; theta < M_PI; theta += 0.1)
      for (double phi = 0; phi < 2 * M_PI; phi += 0.1)
        points.push_back(c + Vec3{std::sin(theta) * std::cos(phi), std::cos(theta),
                                  std::sin(theta) * std::sin(phi)} *
                                 r);
  std::vector<Probe> probes;
  for (const Vec3& p : points) {
    const Vec3 d = Normalize(p - kEye);
    double margin = INFINITY;
    const LocalHit h = TraceLocal(kEye, d, 0, -1, margin);
    if (h.object < 0 || margin < 0.02 || std::abs(h.t - Length(p - kEye)) > 1e-9)
      continue;  // hidden
    const std::optional<Vec3> colour = ShadeLocal(h, d, 2);
    if (!colour) continue;
    const Vec3 n = Dot(h.normal, d) < 0 ? h.normal : -h.normal;
    const bool lightInFront = Dot(n, kLight - p) > 0;
    double unused = INFINITY;
    const bool blocked = TraceLocal(p, Normalize(kLight - p), 0, h.object, unused).object >= 0;
    probes.push_back({p, d, h.object, *colour, lightInFront && blocked});
  }
  return probes;
}

// ---- The same scene placed in the world ------------------------------------------------------

// A rotation (axis (1, 2, 3), 0.7 rad), so that no surface is aligned with an axis and every
// component of every difference the tracer forms carries rounding.
Affine Rotation() {
  const Vec3 k = Normalize(Vec3{1, 2, 3});
  const double c = std::cos(0.7), s = std::sin(0.7);
  const double K[3][3] = {{0, -k.z, k.y}, {k.z, 0, -k.x}, {-k.y, k.x, 0}};
  const double kv[3] = {k.x, k.y, k.z};
  Affine a;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      a.m[i][j] = (i == j ? c : 0) + s * K[i][j] + (1 - c) * kv[i] * kv[j];
  return a;
}

// How the scene is placed: world = R · local + shift; the eye `eyeDistance` from each probe
// along its ray (0: at kEye); the floor's half size; and with objectShift ≠ 0, every object
// written in an object space displaced by objectShift, its transform's translation cancelling
// it (world unchanged).
struct Placement {
  const char* name;
  double eyeDistance = 0;
  Vec3 shift;
  double floorHalf = kFloorHalf;
  double objectShift = 0;
};

Scene WorldScene(const Placement& at) {
  const Affine rotation = Rotation();
  auto world = [&](const Vec3& p) { return rotation.ApplyPoint(p) + at.shift; };
  Scene s;
  s.source = at.name;
  s.background = kBackground;
  s.camera = Camera{world(kEye), world({0, 0.5, 0}), rotation.ApplyVector({0, 1, 0}), 40, 0, 1, 1};
  s.lights.push_back({world(kLight), {1, 1, 1}, true});
  s.materials = {kFloorMaterial, kRedMaterial, kMirrorMaterial};
  // In object space, shapes sit at local + (k, k, k); the transform maps them back.
  const Vec3 k{at.objectShift, at.objectShift, at.objectShift};
  Affine toWorld = rotation;
  const Vec3 back = at.shift - rotation.ApplyVector(k);
  for (int i = 0; i < 3; ++i) toWorld.m[i][3] = (&back.x)[i];
  auto place = [&](const Vec3& p) { return at.objectShift != 0 ? p + k : world(p); };
  auto add = [&](Shape shape, int material) {
    Primitive p;
    p.shape = std::move(shape);
    p.material = material;
    if (at.objectShift != 0) p.transform = toWorld;
    s.objects.push_back(p);
  };
  const double h = at.floorHalf;
  add(Polygon{{place({-h, 0, h}), place({h, 0, h}), place({h, 0, -h}), place({-h, 0, -h})}, {}},
      kFloor);
  add(Sphere{place(kRedCentre), kRedRadius}, kRed);
  add(Sphere{place(kMirrorCentre), kMirrorRadius}, kMirror);
  return s;
}

// The placements for one precision: magnitudes where the offset (1e-4 float, 1e-9 double,
// times about twice the magnitude) stays near 0.2, under the 0.5 the probes keep clear of, and
// far numbers in the objects at 1e6 (float) or 1e10 (double), where a term that missed them
// would be swamped by their rounding (0.06 and 1e-6 against an offset near 1e-3 and 1e-8).
std::vector<Placement> Placements(Precision p) {
  const double far = p == Precision::kFloat ? 1e3 : 1e8, own = p == Precision::kFloat ? 1e6 : 1e10;
  return {
      {"near", 0, {}},
      {"t dominates: the eye far away", far, {}},
      {"the origin dominates: the scene far from the world origin", 0, Vec3{1, -0.7, 0.4} * far},
      {"the object dominates: a huge floor", 0, {}, own},
      {"the object dominates: object spaces far from the world", 0, {}, kFloorHalf, own}};
}

TEST(TraceOffset, ContactShadowAndReflectionsAreTheSameWhicheverMagnitudeDominates) {
  const std::vector<Probe> probes = Probes();
  int shadowed = 0, mirror = 0, red = 0;
  for (const Probe& q : probes) {
    shadowed += q.shadowed;
    mirror += q.object == kMirror;
    red += q.object == kRed;
  }
  // The probes cover the contact shadow, the lit floor, both spheres and their reflections.
  ASSERT_GT(shadowed, 30);
  ASSERT_GT(mirror, 100);
  ASSERT_GT(red, 100);
  ASSERT_GT(int(probes.size()) - shadowed - mirror - red, 500);
  const Affine rotation = Rotation();
  for (const Precision precision : {Precision::kFloat, Precision::kDouble}) {
    const double tolerance = precision == Precision::kFloat ? 3e-3 : 1e-5;
    TraceOptions options;
    options.precision = precision;
    options.depth = 2;
    for (const Placement& at : Placements(precision)) {
      Scene scene = WorldScene(at);
      int wrong = 0, lost = 0;
      for (const Probe& q : probes) {
        const Vec3 d = rotation.ApplyVector(q.direction);
        const Vec3 p = rotation.ApplyPoint(q.point) + at.shift;
        scene.camera.from = at.eyeDistance > 0 ? p - d * at.eyeDistance : scene.camera.from;
        scene.camera.at = scene.camera.from + d;
        const auto tracer = Tracer::Create(scene, options);
        TraceStats stats;
        const PrimaryHit hit = tracer->FirstHit({scene.camera.from, d}, stats);
        if (hit.object != q.object) {
          ADD_FAILURE() << at.name << ": the ray to " << q.point.x << " " << q.point.y << " "
                        << q.point.z << " meets object " << hit.object << ", not " << q.object;
          continue;
        }
        const Vec3 c = tracer->ShadeFromPrimaryHit(hit, stats);
        const bool ok = std::abs(c.x - q.colour.x) <= tolerance &&
                        std::abs(c.y - q.colour.y) <= tolerance &&
                        std::abs(c.z - q.colour.z) <= tolerance;
        if (!ok && wrong++ < 5)
          ADD_FAILURE() << kPrecisionNames.NameOf(precision) << ", " << at.name << ": object "
                        << q.object << " at " << q.point.x << " " << q.point.y << " " << q.point.z
                        << (q.shadowed ? " (in shadow)" : "") << ": " << c.x << " " << c.y << " "
                        << c.z << ", by hand " << q.colour.x << " " << q.colour.y << " "
                        << q.colour.z;
        lost +=
            !ok && !q.shadowed && c.x + c.y + c.z < 0.5 * (q.colour.x + q.colour.y + q.colour.z);
      }
      EXPECT_EQ(wrong, 0) << kPrecisionNames.NameOf(precision) << ", " << at.name << ": " << lost
                          << " of them darker than by hand (a surface shadowing itself) of "
                          << probes.size();
    }
  }
}

// ---- Every kind, alone, with its own numbers far from where it is hit -----------------------

// The image of one object and one white light (no ambient term, no occluder): each pixel
// whose hit faces the light by more than 0.05 (N·L, with the normal computed by hand in
// double) must be lit, and each facing away by more, black.
struct Lit {
  int lit = 0, dark = 0, selfShadowed = 0, litAway = 0;
};

Lit CountSelfShadow(const Scene& s, Precision precision,
                    const std::function<Vec3(const Vec3&)>& normalAt) {
  TraceOptions o;
  o.precision = precision;
  o.depth = 1;
  const auto tracer = Tracer::Create(s, o);
  Lit count;
  TraceStats stats;
  for (int y = 0; y < s.camera.height; ++y)
    for (int x = 0; x < s.camera.width; ++x) {
      PrimaryHit hit;
      const Vec3 c = tracer->TracePixel(x, y, stats, &hit);
      if (hit.object < 0) continue;
      const Vec3 p = s.camera.from + hit.direction * hit.t;
      Vec3 n = normalAt(p);
      if (Dot(n, hit.direction) > 0) n = -n;
      const double nl = Dot(n, Normalize(s.lights[0].position - p));
      const bool black = c.x == 0 && c.y == 0 && c.z == 0;
      if (nl > 0.05) ++count.lit, count.selfShadowed += black;
      if (nl < -0.05) ++count.dark, count.litAway += !black;
    }
  return count;
}

std::string View(const std::string& from, const std::string& at, const std::string& angle,
                 const std::string& light) {
  return "v\nfrom " + from + "\nat " + at + "\nup 0 1 0\nangle " + angle +
         "\nhither 0\nresolution 64 64\nb 0 0 1\nl " + light + " 1 1 1\nf 1 1 1 1 0 0 0 0\n";
}

// Issue 29 item 7's scene: in float, a tilted plane through the world origin whose first
// vertex is far from it showed 320 of its 1536 pixels self-shadowed (its magnitude term, the
// plane offset |n·v0| = 0, did not bound the rounding of n·(v0 − p), which grows with |v0|).
// With it every kind: the plane 1e6 times larger (double: 1280 of 1536 before); the same plane
// (256, 448), a sphere (23, 286) and a cylinder (58, 448) written in an object space 1e4
// (float) or 1e12 (double) away across the axis and moved back by their transform: their
// world numbers are small, their object-space ones are not; and a sphere whose radius is the
// large number (without its term in the offset: 258 in float, 126 in double).
TEST(TraceOffset, NoKindShadowsItselfWhereverItsOwnNumbersAre) {
  const std::string tilted = View("0 0.01 0", "0 -0.3 -10", "50", "0 40 -9000");
  const Vec3 plane = Normalize(Vec3{0, 1, -0.15});  // y = 0.15 z
  auto polygon = [](double k, double dz) {
    auto v = [&](double x, double y, double z) {
      return std::to_string(x * k) + " " + std::to_string(y * k) + " " +
             std::to_string(z * k + dz) + "\n";
    };
    return "p 4\n" + v(-30000, -3000, -20000) + v(30000, -3000, -20000) + v(30000, 300, 2000) +
           v(-30000, 300, 2000);
  };
  for (const Precision precision : {Precision::kFloat, Precision::kDouble}) {
    const bool isFloat = precision == Precision::kFloat;
    const double away = isFloat ? 1e4 : 1e12;
    const std::string shift = "transform 1 0 0 0  0 1 0 " + std::to_string(-away) + "  0 0 1 0\n";
    const std::string zShift = "transform 1 0 0 0  0 1 0 0  0 0 1 " + std::to_string(-away) + "\n";
    const std::string xShift = "transform 1 0 0 " + std::to_string(-away) + "  0 1 0 0  0 0 1 0\n";
    const std::string sideLight = View("0 0 5", "0 0 0", "30", "5 0.3 0");
    const double radius = isFloat ? 1e5 : 1e9;
    const std::string giant = std::to_string(radius);
    // A needle: a unit sphere rotated 45° about z, then stretched 3e4 times along x.
    Affine needle;
    const double c45 = std::sqrt(0.5);
    const double rows[3][3] = {{3e4 * c45, -3e4 * c45, 0}, {c45, c45, 0}, {0, 0, 1}};
    std::string needleNff = "transform";
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) needle.m[i][j] = rows[i][j];
      needle.m[i][3] = 0;
      char row[96];
      std::snprintf(row, sizeof row, " %.17g %.17g %.17g 0 ", rows[i][0], rows[i][1], rows[i][2]);
      needleNff += row;
    }
    const Affine fromNeedle = needle.Inverse();
    struct Case {
      std::string name, nff;
      std::function<Vec3(const Vec3&)> normal;
      int minimumLit;
    } cases[] = {
        {"the tilted plane", tilted + polygon(isFloat ? 1 : 1e6, 0),
         [&](const Vec3&) { return plane; }, 1536},
        {"the tilted plane, 1e-4 its size, in a far object space",
         tilted + zShift + polygon(1e-4, away), [&](const Vec3&) { return plane; }, 1000},
        {"a sphere in a far object space",
         sideLight + shift + "s 0 " + std::to_string(away) + " 0 1\n",
         [](const Vec3& p) { return p; }, 300},
        {"a cylinder in a far object space",
         sideLight + xShift + "c " + std::to_string(away) + " -1 0 1 " + std::to_string(away) +
             " 1 0 1\n",
         [](const Vec3& p) {
           return Vec3{p.x, 0, p.z};
         },
         300},
        {"a sphere of radius 1e5 (float) or 1e9 (double) as the floor, seen from near its top",
         View("0 2 5", "0 0 0", "40", "5 8 3") + "s 0 -" + giant + " 0 " + giant + "\n",
         [&](const Vec3& p) {
           return p + Vec3{0, radius, 0};
         },
         4000},
        // A boundary: the needle's ‖A‖∞‖A⁻¹‖∞ is 3e4, but what it multiplies moves the hit
        // point along the surface, not across it; the offset needs no term for it.
        {"a needle ellipsoid 3e4:1",
         View("30 0 6", "30 0 0", "30", "3 5 4") + needleNff + "\ns 0 0 0 1\n",
         [&](const Vec3& p) { return fromNeedle.ApplyTransposed(fromNeedle.ApplyPoint(p)); }, 1000},
    };
    for (const Case& c : cases) {
      const Scene s = ParseNffOrThrow(c.nff, "kind.nff");
      const Lit n = CountSelfShadow(s, precision, c.normal);
      const std::string what = std::string(kPrecisionNames.NameOf(precision)) + ", " + c.name;
      EXPECT_GE(n.lit, c.minimumLit) << what;
      EXPECT_EQ(n.selfShadowed, 0) << what << ": of " << n.lit << " pixels facing the light";
      EXPECT_EQ(n.litAway, 0) << what << ": of " << n.dark << " pixels facing away";
    }
  }
}

}  // namespace
}  // namespace zephyr
