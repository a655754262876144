// hosts/scene/gen.cpp — the scene generators (`zephyr gen` is hosts/cmd/gen.cpp).
#include "hosts/scene/gen.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "fixed/check.h"
#include "hosts/scene/nff.h"

namespace zephyr {

namespace {

// SplitMix64 (Steele, Lea, Flood 2014): tiny, and the same sequence everywhere.
class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double Uniform() { return double(Next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }

 private:
  uint64_t state_;
};

int AddMaterial(Scene& s, const Material& m) {
  auto it = std::find(s.materials.begin(), s.materials.end(), m);
  if (it != s.materials.end()) return int(it - s.materials.begin());
  s.materials.push_back(m);
  return int(s.materials.size()) - 1;
}

void Add(Scene& s, int material, Shape shape, std::optional<Affine> transform = std::nullopt) {
  Primitive p;
  p.shape = std::move(shape);
  p.material = material;
  p.transform = transform;
  s.objects.push_back(std::move(p));
}

// An orthonormal frame around a unit axis.
void Frame(const Vec3& axis, Vec3& u, Vec3& v) {
  const Vec3 helper = std::abs(axis.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  u = Normalize(Cross(axis, helper));
  v = Cross(axis, u);
}

void Flake(Scene& s, int material, const Vec3& centre, double radius, const Vec3& axis, int depth) {
  Add(s, material, Sphere{centre, radius});
  if (depth == 0) return;
  Vec3 u, v;
  Frame(axis, u, v);
  const double childRadius = radius / 3;
  // Six children around the equator, three above it (as SPD `balls` arranges them).
  for (int i = 0; i < 9; ++i) {
    const bool top = i >= 6;
    const double azimuth = top ? (30.0 + 120.0 * (i - 6)) * M_PI / 180 : 60.0 * i * M_PI / 180;
    const double elevation = top ? 54.7356103172 * M_PI / 180 : 0.0;
    const Vec3 dir = u * (std::cos(elevation) * std::cos(azimuth)) +
                     v * (std::cos(elevation) * std::sin(azimuth)) + axis * std::sin(elevation);
    Flake(s, material, centre + dir * (radius + childRadius), childRadius, Normalize(dir),
          depth - 1);
  }
}

}  // namespace

Scene GenerateRandomSpheres(const RandomSpheresOptions& o) {
  if (o.count < 1 || o.count > kMaxRandomSpheres)
    throw UserError("random spheres: the count must be 1.." + std::to_string(kMaxRandomSpheres) +
                    ", got " + std::to_string(o.count));
  Scene s;
  s.source = "gen spheres --count " + std::to_string(o.count) + " --seed " + std::to_string(o.seed);
  s.camera = Camera{{0, 0, 12}, {0, 0, 0}, {0, 1, 0}, 30, 0.001, o.width, o.height};
  s.background = {0.10, 0.15, 0.30};
  s.lights = {Light{{-10, 10, 20}, {0.7, 0.7, 0.7}}, Light{{10, 6, 15}, {0.6, 0.6, 0.6}}};
  SplitMix64 rng(o.seed);
  // Spheres fill ~8 % of a 4.4 × 4.4 × 6 box in the middle of the view.
  const double half = 2.2, zLo = -4, zHi = 2;
  const double base = std::cbrt(2.2 / o.count);
  std::vector<Sphere> placed;
  for (int i = 0; i < o.count; ++i) {
    Sphere sp;
    for (int attempt = 0; attempt < 200; ++attempt) {
      sp.radius = base * rng.Uniform(0.6, 1.0);
      sp.centre = {rng.Uniform(-half + sp.radius, half - sp.radius),
                   rng.Uniform(-half + sp.radius, half - sp.radius), rng.Uniform(zLo, zHi)};
      bool clear = true;
      for (const Sphere& q : placed)
        if (Length(q.centre - sp.centre) < q.radius + sp.radius) {
          clear = false;
          break;
        }
      if (clear) break;  // after 200 tries an overlapping sphere is kept
    }
    placed.push_back(sp);
    const double kind = rng.Uniform();
    const Vec3 colour{rng.Uniform(0.2, 1.0), rng.Uniform(0.2, 1.0), rng.Uniform(0.2, 1.0)};
    Material m;
    if (kind < 0.6) {  // diffuse with a small highlight
      m = Material{colour, 0.8, 0.1, 30, 0, 1};
    } else if (kind < 0.8) {  // mirror
      m = Material{colour, 0.2, 0.8, 100, 0, 1};
    } else {  // glass
      m = Material{{1, 1, 1}, 0.05, 0.1, 100, 0.85, 1.5};
    }
    Add(s, AddMaterial(s, m), sp);
  }
  return s;
}

Scene GenerateSphereflake(int depth, int width, int height) {
  if (depth < 0 || depth > kMaxFlakeDepth)
    throw UserError("sphereflake: the depth must be 0..6 (depth 6 is 597,871 spheres), got " +
                    std::to_string(depth));
  Scene s;
  s.source = "gen flake --depth " + std::to_string(depth);
  // SPD `balls`: view, lights, floor and materials.
  s.camera = Camera{{2.1, 1.3, 1.7}, {0, 0, 0}, {0, 0, 1}, 45, 0.01, width, height};
  s.background = {0.078, 0.361, 0.753};
  s.lights = {Light{{4, 3, 2}, {1, 1, 1}}, Light{{1, -4, 4}, {1, 1, 1}},
              Light{{-3, 1, 5}, {1, 1, 1}}};
  const int floor = AddMaterial(s, Material{{1, 0.75, 0.33}, 0.8, 0, 100000, 0, 1});
  Add(s, floor, Polygon{{{12, 12, -0.5}, {-12, 12, -0.5}, {-12, -12, -0.5}, {12, -12, -0.5}}, {}});
  const int balls = AddMaterial(s, Material{{1, 0.9, 0.7}, 0.5, 0.5, 3.0827, 0, 1});
  Flake(s, balls, {0, 0, 0}, 0.5, {0, 0, 1}, depth);
  return s;
}

Scene GenerateTransformedShowcase(int width, int height) {
  Scene s;
  s.source = "gen showcase";
  s.camera = Camera{{0, -9, 4}, {0, 0, 0.6}, {0, 0, 1}, 35, 0.01, width, height};
  s.background = {0.15, 0.2, 0.3};
  s.lights = {Light{{-6, -8, 10}, {0.8, 0.8, 0.8}}, Light{{8, -4, 6}, {0.5, 0.5, 0.5}}};
  const int floor = AddMaterial(s, Material{{0.8, 0.8, 0.7}, 0.8, 0, 1, 0, 1});
  Add(s, floor, Polygon{{{6, 6, 0}, {-6, 6, 0}, {-6, -6, 0}, {6, -6, 0}}, {}});
  auto rotZ = [](double deg) {
    const double c = std::cos(deg * M_PI / 180), sn = std::sin(deg * M_PI / 180);
    Affine a;
    a.m[0][0] = c;
    a.m[0][1] = -sn;
    a.m[1][0] = sn;
    a.m[1][1] = c;
    return a;
  };
  auto rotX = [](double deg) {
    const double c = std::cos(deg * M_PI / 180), sn = std::sin(deg * M_PI / 180);
    Affine a;
    a.m[1][1] = c;
    a.m[1][2] = -sn;
    a.m[2][1] = sn;
    a.m[2][2] = c;
    return a;
  };
  auto move = [](double sx, double sy, double sz, Vec3 t) {
    Affine a;
    a.m[0][0] = sx;
    a.m[1][1] = sy;
    a.m[2][2] = sz;
    a.m[0][3] = t.x;
    a.m[1][3] = t.y;
    a.m[2][3] = t.z;
    return a;
  };
  // An ellipsoid: a unit sphere scaled, rotated and moved.
  const int red = AddMaterial(s, Material{{0.9, 0.2, 0.2}, 0.7, 0.3, 40, 0, 1});
  Add(s, red, Sphere{{0, 0, 0}, 1},
      move(1, 1, 1, {-1.8, 0.5, 0.7}) * rotZ(30) * move(1.4, 0.6, 0.7, {}));
  // A sheared cylinder: x += 0.5 z.
  Affine shear;
  shear.m[0][2] = 0.5;
  const int green = AddMaterial(s, Material{{0.2, 0.8, 0.3}, 0.8, 0.1, 20, 0, 1});
  Add(s, green, Cone{{0, 0, 0}, 0.45, {0, 0, 1.6}, 0.45}, move(1, 1, 1, {0.2, 1.2, 0}) * shear);
  // A cone lying on its side.
  const int blue = AddMaterial(s, Material{{0.3, 0.4, 0.9}, 0.7, 0.2, 60, 0, 1});
  Add(s, blue, Cone{{0, 0, 0}, 0.6, {0, 0, 1.5}, 0.1},
      move(1, 1, 1, {1.6, -0.2, 0.6}) * rotZ(-40) * rotX(80));
  // A transformed cube: six unit squares under a rotation and a non-uniform scale.
  const int gold = AddMaterial(s, Material{{0.9, 0.7, 0.2}, 0.6, 0.3, 80, 0, 1});
  const Affine cube = move(1, 1, 1, {0.2, -1.6, 0.5}) * rotZ(25) * move(0.9, 0.6, 0.5, {});
  for (int axis = 0; axis < 3; ++axis) {
    for (double side : {-1.0, 1.0}) {
      Polygon face;
      for (int k = 0; k < 4; ++k) {
        const double a = (k == 1 || k == 2) ? 1 : -1, b = (k >= 2) ? 1 : -1;
        double p[3];
        p[axis] = side;
        p[(axis + 1) % 3] = a;
        p[(axis + 2) % 3] = b;
        face.vertices.push_back({p[0], p[1], p[2]});
      }
      Add(s, gold, face, cube);
    }
  }
  return s;
}

}  // namespace zephyr
