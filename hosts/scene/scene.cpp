#include "hosts/scene/scene.h"

#include <algorithm>

namespace zephyr {

std::string SourceLocation::ToString() const {
  return file + ":" + std::to_string(line) + ":" + std::to_string(column);
}

const char* ShapeKindName(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::kSphere: return "sphere";
    case ShapeKind::kCone: return "cone";
    case ShapeKind::kPolygon: return "polygon";
  }
  return "?";
}

double Scene::Extent() const {
  double r = Length(camera.from);
  auto grow = [&](const std::optional<Affine>& xf, const Vec3& p, double radius) {
    if (xf) {
      // Bound the transformed radius by the largest column norm times sqrt(3).
      double scale = 0;
      for (int c = 0; c < 3; ++c)
        scale = std::max(scale, Length(xf->ApplyVector(Vec3{c == 0 ? 1.0 : 0, c == 1 ? 1.0 : 0,
                                                             c == 2 ? 1.0 : 0})));
      r = std::max(r, Length(xf->ApplyPoint(p)) + radius * scale * 1.7320508075688772);
    } else {
      r = std::max(r, Length(p) + radius);
    }
  };
  for (const Primitive& o : objects) {
    if (auto* s = std::get_if<Sphere>(&o.shape)) {
      grow(o.transform, s->center, s->radius);
    } else if (auto* c = std::get_if<Cone>(&o.shape)) {
      grow(o.transform, c->base, c->baseRadius);
      grow(o.transform, c->apex, c->apexRadius);
    } else if (auto* p = std::get_if<Polygon>(&o.shape)) {
      for (const Vec3& v : p->vertices) grow(o.transform, v, 0);
    }
  }
  return std::max(r, 1e-300);
}

}  // namespace zephyr
