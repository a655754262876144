#include "hosts/scene/scene.h"

#include <algorithm>
#include <cmath>

#include "fixed/named.h"

namespace zephyr {

std::string SourceLocation::ToString() const {
  return file + ":" + std::to_string(line) + ":" + std::to_string(column);
}

Vec3 NewellNormal(const std::vector<Vec3>& v) {
  Vec3 n;
  for (size_t i = 0; i < v.size(); ++i) {
    const Vec3& a = v[i];
    const Vec3& b = v[(i + 1) % v.size()];
    n += Vec3{(a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y)};
  }
  return n;
}

WorldSpacePolygon ToWorldSpace(const Primitive& p) {
  const Polygon& q = std::get<Polygon>(p.shape);
  WorldSpacePolygon w{q.vertices, q.normals, {}, 1};
  if (p.transform) {
    const Affine inv = p.transform->Inverse();
    for (Vec3& x : w.vertices) x = p.transform->ApplyPoint(x);
    for (Vec3& n : w.normals) n = inv.ApplyTransposed(n);
    w.front = p.transform->RelativeDeterminant() < 0 ? -1 : 1;
  }
  w.normal = Normalize(ScaledDown(NewellNormal(w.vertices)));
  return w;
}

const char* ShapeKindName(ShapeKind kind) {
  static constexpr NamedValues<ShapeKind, 3> kNames{{{{ShapeKind::kSphere, "sphere"},
                                                      {ShapeKind::kCone, "cone"},
                                                      {ShapeKind::kPolygon, "polygon"}}}};
  return kNames.NameOf(kind);
}

Vec3 Scene::LightColour(size_t i) const {
  const Light& l = lights.at(i);
  if (l.colourGiven) return l.colour;
  const double n = double(lights.size());
  const double each = std::sqrt(n) / (2 * n);
  return {each, each, each};
}

double Scene::Ambient() const {
  for (const Light& l : lights)
    if (!l.colourGiven) return std::sqrt(double(lights.size())) / (2 * double(lights.size()));
  return 0;
}

namespace {

// ‖A‖∞ of the linear part (largest row sum of |a_ij|): |A v|∞ <= ‖A‖∞ |v|∞.
double RowNorm(const Affine& a) {
  double n = 0;
  for (int r = 0; r < 3; ++r)
    n = std::max(n, std::abs(a.m[r][0]) + std::abs(a.m[r][1]) + std::abs(a.m[r][2]));
  return n;
}

// The points and radii that bound a primitive in its own coordinates.
template <typename F>
void ForEachBoundPoint(const Primitive& o, F&& f) {
  if (auto* s = std::get_if<Sphere>(&o.shape)) {
    f(s->centre, s->radius);
  } else if (auto* c = std::get_if<Cone>(&o.shape)) {
    f(c->base, c->baseRadius);
    f(c->apex, c->apexRadius);
  } else if (auto* p = std::get_if<Polygon>(&o.shape)) {
    for (const Vec3& v : p->vertices) f(v, 0.0);
  }
}

}  // namespace

std::optional<MagnitudeFault> FindMagnitudeOver(const Scene& scene, double limit) {
  auto over = [&](double m) { return !(m <= limit); };  // NaN and inf are over too
  const Camera& c = scene.camera;
  if (over(MaxAbs(c.from))) return MagnitudeFault{c.where, "the eye ('from')", MaxAbs(c.from)};
  if (over(MaxAbs(c.at))) return MagnitudeFault{c.where, "the look-at point ('at')", MaxAbs(c.at)};
  double world = std::max(MaxAbs(c.from), MaxAbs(c.at));
  for (const Light& l : scene.lights) {
    if (over(MaxAbs(l.position))) return MagnitudeFault{l.where, "light", MaxAbs(l.position)};
    world = std::max(world, MaxAbs(l.position));
  }
  for (const Primitive& o : scene.objects) {
    double bound = 0;
    const double scale = o.transform ? RowNorm(*o.transform) : 1.0;
    ForEachBoundPoint(o, [&](const Vec3& p, double r) {
      bound = std::max(bound, MaxAbs(o.transform ? o.transform->ApplyPoint(p) : p) + r * scale);
    });
    if (over(bound)) return MagnitudeFault{o.where, ShapeKindName(o.Kind()), bound};
    world = std::max(world, bound);
  }
  // In an object's own coordinates: the scene mapped by T⁻¹ (ray origins and hit points),
  // directions stretched by ‖T⁻¹‖ (spheres renormalise theirs), cones' slopes.
  for (const Primitive& o : scene.objects) {
    double own = 0;
    ForEachBoundPoint(o, [&](const Vec3& p, double r) { own = std::max(own, MaxAbs(p) + r); });
    double points = std::max(own, world), stretch = 1;
    if (o.transform) {
      const Affine inv = o.transform->Inverse();
      const double n = RowNorm(inv);
      points = std::max(own, n * world + MaxAbs(Vec3{inv.m[0][3], inv.m[1][3], inv.m[2][3]}));
      if (o.Kind() != ShapeKind::kSphere) stretch = std::max(1.0, n);
    }
    double slope = 0;
    if (auto* cn = std::get_if<Cone>(&o.shape))
      slope = std::abs(cn->apexRadius - cn->baseRadius) / Length(ScaledDown(cn->apex - cn->base)) /
              MaxAbs(cn->apex - cn->base);
    const double m = points * stretch * (1 + slope) * (1 + slope);
    if (over(m))
      return MagnitudeFault{o.where,
                            std::string(ShapeKindName(o.Kind())) +
                                " (in its own coordinates, "
                                "with its transform and slope)",
                            m};
  }
  return std::nullopt;
}

}  // namespace zephyr
