// hosts/scene/scene.h — a scene as every method sees it: camera, lights, materials and the
// primitives in scene-file order (docs/background.md, "The ray tracer"). Everything is double; a
// tracer templated on float converts when it prepares its own copy.
//
// The object index used everywhere (primary-hit matrices, --dump-primary, accuracy
// reports) is the position in Scene::objects, i.e. file order across all primitive kinds.
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "hosts/scene/geometry.h"

namespace zephyr {

// Where an item came from in its scene file (1-based line and column).
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;
  std::string ToString() const;  // "file:line:column"
};

// NFF `v` block. angle is the full vertical field of view in degrees between the centres of
// the top and bottom pixel rows (docs/scene-format.md); hither is the near clipping distance along
// each primary ray.
struct Camera {
  Vec3 from, at, up;
  double angleDegrees = 45;
  double hither = 0;
  int width = 0, height = 0;
  SourceLocation where = {};  // the `from` line (messages about the eye)
};

// NFF `l x y z [r g b]`. Without a colour (colourGiven false) the intensity comes from
// Scene::LightColour, SPD's rule.
struct Light {
  Vec3 position;
  Vec3 colour{1, 1, 1};
  bool colourGiven = true;
  SourceLocation where = {};
};

// NFF `f r g b Kd Ks Shine T ior` (docs/shading.md says how each term is used).
struct Material {
  Vec3 colour{1, 1, 1};
  double kd = 1, ks = 0, shine = 0, t = 0, ior = 1;
  bool operator==(const Material&) const = default;
};

struct Sphere {
  Vec3 centre;  // scene units
  double radius = 1;
};

// NFF `c`: a truncated cone between base and apex (a cylinder when the radii are equal),
// open — no caps.
struct Cone {
  Vec3 base;
  double baseRadius = 1;
  Vec3 apex;
  double apexRadius = 1;
};

// NFF `p` (normals empty) or `pp` (one normal per vertex, interpolated across the face).
// Planar, at least three vertices; the inside is decided by the even-odd rule, so the
// concave gear outlines of SPD `gears` work too.
struct Polygon {
  std::vector<Vec3> vertices;
  std::vector<Vec3> normals;
};

using Shape = std::variant<Sphere, Cone, Polygon>;
enum class ShapeKind { kSphere = 0, kCone = 1, kPolygon = 2 };
inline constexpr int kShapeKinds = 3;
const char* ShapeKindName(ShapeKind kind);  // "sphere", "cone", "polygon"

struct Primitive {
  Shape shape;
  int material = 0;                 // index into Scene::materials
  std::optional<Affine> transform;  // object -> world (docs/scene-format.md); none = identity
  SourceLocation where;

  ShapeKind Kind() const { return static_cast<ShapeKind>(shape.index()); }
};

// Newell's normal of a polygon with vertices v (not unit: its length is twice the area; it
// points to the side from which v winds counter-clockwise), summed edge by edge from vertex 0.
// The one sum the reader's area test and every polygon's world form start from.
Vec3 NewellNormal(const std::vector<Vec3>& v);

// A polygon (or patch) as every ray test takes it — the host tracer, the primary pass, the
// bounces: its vertices in world space (the transform applied), its vertex normals mapped by
// the inverse transpose (a patch's; empty for a flat polygon), the unit Newell normal of the
// world vertices, and `front`, −1 under a mirroring transform (its world winding is reversed,
// so front·normal keeps the object's front its front) else 1. Made once here so the three
// agree bit for bit.
struct WorldSpacePolygon {
  std::vector<Vec3> vertices, normals;
  Vec3 normal;    // unit: Normalize(ScaledDown(NewellNormal(vertices)))
  int front = 1;  // ±1
};
// p's world form; p must be a polygon (std::bad_variant_access otherwise: a caller's bug).
WorldSpacePolygon ToWorldSpace(const Primitive& p);

struct Scene {
  Camera camera;
  Vec3 background{0, 0, 0};
  std::vector<Light> lights;
  std::vector<Material> materials;
  std::vector<Primitive> objects;     // file order: the object index every method reports
  std::string source;                 // file name, for messages and reports
  std::vector<std::string> warnings;  // "file:line:column: warning: ..." (printed by render)

  // The intensity every method shades with for light i: its colour if the file gave one;
  // otherwise √N/(2N) in each channel for the scene's N lights (SPD readme, "so that the
  // scene does not saturate"; docs/scene-format.md).
  Vec3 LightColour(size_t i) const;
  // The ambient intensity A (shading adds A · Kd · C at every hit, shadowed or not): √N/(2N)
  // when some light has no colour (the SPD readme's ambient term), else 0.
  double Ambient() const;
};

// Where a value of the scene is larger than arithmetic can square: the item's location,
// what it is and the magnitude found.
struct MagnitudeFault {
  SourceLocation where;
  std::string what;  // "the eye ('from')", "light", "sphere", ...
  double magnitude;
};

// The tracers form products of two coordinates and sums of a few such products (|f|², the
// cone's quadratic, a polygon's edge functions); a scene whose values stay within `limit`
// keeps them finite when limit² · 64 is below the arithmetic's largest number. Checked per
// item: the eye and `at`, each light, each object's world-space extent, and for an object
// with a transform or a cone's slope the magnitudes it meets in its own coordinates (the
// eye, lights and scene mapped by T⁻¹, times ‖T⁻¹‖ and (1 + |slope|)²). Returns the first
// item over the limit, in file order.
std::optional<MagnitudeFault> FindMagnitudeOver(const Scene& scene, double limit);

// The limits the tracers use (docs/scene-format.md): sqrt(largest finite) / 64, rounded
// down to a power of ten: 1e150 for double (sqrt(1.8e308) = 1.3e154), 1e17 for float
// (sqrt(3.4e38) = 1.8e19).
inline constexpr double kMagnitudeLimitDouble = 1e150;
inline constexpr double kMagnitudeLimitFloat = 1e17;

}  // namespace zephyr
