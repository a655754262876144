// hosts/wavefront/program.cpp — one wavefront bounce on the array (hosts/wavefront/program.h,
// docs/wavefront.md "The bounce program" and "Error bounds").
#include "hosts/wavefront/program.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "fixed/check.h"
#include "hosts/simd/bounds.h"
#include "hosts/simd/ops.h"

namespace zephyr::wavefront {

using bitserial::Machine;
using bitserial::Multi;
using bitserial::Uni;
using fixed::Fixed;
using fixed::Format;
using simd::IntBitsFor;
using simd::Tight;

SecondaryPlan PlanSecondary(const Scene& scene, int fracBits, double primaryTError) {
  if (fracBits < 8 || fracBits > 40)
    throw UserError("the secondary rays' fraction bits must be 8..40, got " +
                    std::to_string(fracBits));
  SecondaryPlan p;
  double extent = MaxAbs(scene.camera.from), light = 0, maxIor = 1, minRadius = 1e300;
  // Each polygon's world vertices and front normal, as the tracer takes them.
  std::vector<std::vector<Vec3>> worldVertices;
  std::vector<Vec3> worldNormals;
  for (const Primitive& o : scene.objects) {
    const auto* s = std::get_if<Sphere>(&o.shape);
    const auto* q = std::get_if<Polygon>(&o.shape);
    const bool sphere = s && !o.transform, flat = q && q->normals.empty();
    if (!sphere && !flat)
      throw UserError(o.where.ToString() +
                      ": --method array traces untransformed spheres and flat polygons only " +
                      "(docs/wavefront.md); this object is " +
                      (s   ? std::string("a transformed sphere")
                       : q ? std::string("a polygon patch (vertex normals)")
                           : "a " + std::string(ShapeKindName(o.Kind()))));
    p.objects.push_back({sphere, int(sphere ? p.spheres.size() + 0 : worldVertices.size())});
    if (sphere) {
      extent = std::max(extent, MaxAbs(s->centre) + s->radius);
      minRadius = std::min(minRadius, s->radius);
      p.spheres.emplace_back();  // filled below
    } else {
      std::vector<Vec3> v = q->vertices;
      int front = 1;
      if (o.transform) {
        for (Vec3& x : v) x = o.transform->ApplyPoint(x);
        front = o.transform->RelativeDeterminant() < 0 ? -1 : 1;
      }
      Vec3 n;  // Newell's normal, as hosts/trace/tracer.cpp Prepare
      for (size_t i = 0; i < v.size(); ++i) {
        const Vec3& a = v[i];
        const Vec3& b = v[(i + 1) % v.size()];
        n += Vec3{(a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y)};
      }
      n = Normalize(ScaledDown(n));
      for (const Vec3& x : v) extent = std::max(extent, MaxAbs(x));
      worldVertices.push_back(v);
      worldNormals.push_back(n * double(front));
    }
    const Material& m = scene.materials[o.material];
    maxIor = std::max({maxIor, m.ior, 1 / m.ior});
    p.anyMirror |= m.ks > 0;
    p.anyTransparent |= m.t > 0;
  }
  for (const Light& l : scene.lights) light = std::max(light, MaxAbs(l.position));
  const int F = fracBits;
  const double u = std::ldexp(1.0, -F);
  p.fracBits = F, p.ulp = u;
  p.intBits = IntBitsFor(extent) + 1;
  const int I = p.intBits;
  p.coord = Format::Signed(I, F);
  p.offset = Format::Signed(I + 1, F);
  p.t = Format::Signed(I + 2, F);
  p.direction = Format::Signed(1, F);
  const int il = IntBitsFor(light + extent) + 1;
  p.toLight = Format::Signed(il, F);
  p.distance = Format::Unsigned(il, F);
  p.eta = Format::Unsigned(IntBitsFor(maxIor) + 1, F);
  p.unit = Format::Unsigned(1, F);
  p.index = Format::Unsigned(IntBitsFor(double(scene.objects.size()) + 1) + 1, 0);
  // The host reads coordinates as 64-bit integers and the engine's widest value has 128 bits
  // (the polygon edge functions' are the widest here).
  const int widest = p.polygons.empty() && worldVertices.empty() ? p.t.Width() : 2 * I + 8 + F;
  if (p.coord.Width() > 62 || widest > 120)
    throw UserError("the scene's extent (" + fmt::format("{:.6g}", extent) + ") needs " +
                    std::to_string(I) + " integer bits: with " + std::to_string(F) +
                    " fraction bits a coordinate would take " + std::to_string(p.coord.Width()) +
                    " bits (at most 62: the host reads it as a 64-bit integer) and the widest "
                    "value " +
                    std::to_string(widest) +
                    " (at most 120): use fewer fraction "
                    "bits, at most " +
                    std::to_string(std::min(61 - I, worldVertices.empty() ? 61 - I : 112 - 2 * I)));
  p.edgeVector = Format::Signed(I + 2, F);
  p.edgeCross = Format::Signed(2 * I + 5, F);
  p.edgeValue = Format::Signed(2 * I + 7, F);
  // A direction normalised on the array (d·(1/|d|), each step floor-rounded): | |d|² − 1 |
  // below 12u (docs/wavefront.md, "Error bounds"); 16u taken.
  p.directionError = 16 * u;
  const double diameter = 2 * std::sqrt(3.0) * extent;
  const double eTca = 4 * u;    // Σ d_k (c_k − o_k): c rounded to nearest, 3 floor products
  const double eCross = 3 * u;  // f_j d_l − f_l d_j
  // Polygons (docs/wavefront.md, "Error bounds"): each edge function's error from the vertices
  // rounded to nearest (|p − o|, |q − o| <= the diameter D) and five floor products; t =
  // (n·v0 − n·o)/(n·d) with n and n·v0 rounded to nearest, where |n·d| >= the parallel band.
  {
    const double D = diameter;
    const double eNum = 3 * std::ldexp(1.0, I) * u / 2 + 3 * u + u / 2, eNd = 1.75 * u / 2 + 3 * u;
    const double edgeBand = 1.25 * (1.75 * (2 * D * u + 2 * u + u * u) + 3 * u);
    const double tError = (eNum + D * eNd) / (p.parallelBand - eNd) + D * p.directionError + 2 * u;
    for (size_t j = 0; j < worldVertices.size(); ++j) {
      PolygonTerms t;
      const Vec3& n = worldNormals[j];
      for (int k = 0; k < 3; ++k) t.normal[k] = Tight(n[k], F);
      t.offset = Tight(Dot(n, worldVertices[j][0]), F);
      for (const Vec3& x : worldVertices[j])
        t.vertices.push_back({Tight(x.x, F), Tight(x.y, F), Tight(x.z, F)});
      t.groups = PolygonEdgeGroups(worldVertices[j], n);
      t.edgeBand = edgeBand, t.tError = tError;
      p.polygons.push_back(t);
    }
  }
  for (size_t j = 0; j < scene.objects.size(); ++j) {
    const Primitive& o = scene.objects[j];
    const Material& m = scene.materials[o.material];
    if (!p.objects[j].sphere) {
      PolygonTerms& t = p.polygons[p.objects[j].index];
      t.transparency = m.t, t.ior = m.ior;
      p.tError = std::max(p.tError, t.tError);
      continue;
    }
    const Sphere& s = std::get<Sphere>(o.shape);
    SphereTerms t;
    for (int k = 0; k < 3; ++k) t.centre[k] = Tight(s.centre[k], F);
    t.r2 = Tight(s.radius * s.radius, F);
    t.inverseRadius = Tight(1 / s.radius, F);
    const int R = IntBitsFor(s.radius);
    t.clamped = Format::Signed(R, F), t.square = Format::Unsigned(2 * R + 2, F);
    t.disc = Format::Signed(2 * R + 2, F), t.root = Format::Unsigned(R + 1, F);
    const double r2 = s.radius * s.radius;
    // The band as the primary pass's (the radius/8 floor), grown by the direction's
    // non-unit length: r² − |f×d|² against r² − |f×d̂|² differs by <= (r² + G)·δ.
    double g = r2 / 64, eDisc = 0;
    for (int it = 0; it < 8; ++it) {
      const auto [band, e] = simd::GrazingBand(r2, g, eCross, u / 2, std::ldexp(1.0, R), u);
      eDisc = e + 1.01 * p.directionError * (r2 + band);
      g = std::max(band, 2 * eDisc);
      if (2 * eDisc <= g && band <= g) break;
    }
    t.grazeBand = g;
    // f·d along the array's d against f·d̂: |f|·| |d| − 1 |.
    const double eDir = diameter * p.directionError;
    t.tError = eTca + eDir + eDisc / std::sqrt(g) + 2 * u;
    t.slack = std::max(t.tError, eTca + eDir + std::sqrt(g + eDisc)) + u;
    t.transparency = m.t, t.ior = m.ior;
    for (const Light& l : scene.lights)
      t.lightOutside.push_back(Length(l.position - s.centre) > s.radius);
    p.tError = std::max(p.tError, t.tError);
    p.spheres[p.objects[j].index] = t;
  }
  p.primaryTError = primaryTError;
  // A hit point's distance from its surface: t's error along |d| <= 1 + δ, t·| |d| − 1 |, and
  // the point's own rounding; a ray leaving it ignores roots up to four times that.
  const double pointError =
      1.01 * std::max(p.tError, primaryTError) + diameter * p.directionError + 2 * u;
  // The surface a ray leaves is handled by the rule above (never met again, or at its far
  // root), so the array's own cut-off only keeps roots at the origin from counting: 2(E + u).
  // The host, which traces an uncertain ray without that rule, skips four times the point's
  // error instead.
  p.epsilon = 2 * (p.tError + u);
  p.hostOffset = 4 * (p.tError + pointError);
  for (const Light& l : scene.lights)
    for (int k = 0; k < 3; ++k) p.lights[k].push_back(Tight(l.position[k], F));
  return p;
}

namespace {

Multi Loaded(Machine& m, Format f, const std::vector<int64_t>& raw) {
  Multi x(m, f, "input");
  x.LoadRaw(raw);
  return x;
}

Multi Dot(const Multi (&a)[3], const Multi (&b)[3], Format out) {
  return Add(Add(Mul(a[0], b[0], out), Mul(a[1], b[1], out), out), Mul(a[2], b[2], out), out);
}

Multi Const(Machine& m, double x, int frac) { return Broadcast(m, Tight(x, frac)); }

// d·(1/|d|), floor-rounded at each step (|d| near 1: the children of unit directions).
void Normalise(Multi (&d)[3], const SecondaryPlan& p) {
  const int F = p.fracBits;
  const Multi len = Sqrt(simd::SumOfSquares(d, Format::Unsigned(2, F)), Format::Unsigned(1, F));
  const Multi inv = Div(Uni{Fixed{Format::Unsigned(1, 0), 1}}, len, Format::Unsigned(2, F));
  for (int k = 0; k < 3; ++k) d[k] = Mul(d[k], inv, p.direction);
}

// One sphere along o + t·d: the two roots t0 <= t1 (meaningful where disc >= 0), the
// discriminant and whether it is within the grazing band.
struct Roots {
  Multi t0, t1, disc, grazing;
};

Roots SphereRoots(Machine& m, const Multi (&o)[3], const Multi (&d)[3], const SphereTerms& s,
                  const SecondaryPlan& p) {
  Multi f[3];
  for (int k = 0; k < 3; ++k) f[k] = Sub(Uni{s.centre[k]}, o[k], p.offset);
  const Multi tca = Dot(d, f, p.t);
  Multi sum;
  {
    const Multi c[3] = {Sub(Mul(f[1], d[2], p.t), Mul(f[2], d[1], p.t), p.t),
                        Sub(Mul(f[2], d[0], p.t), Mul(f[0], d[2], p.t), p.t),
                        Sub(Mul(f[0], d[1], p.t), Mul(f[1], d[0], p.t), p.t)};
    simd::WithExpectedSaturation(m, [&] {
      Multi sq[3];
      for (int k = 0; k < 3; ++k)
        sq[k] = Square(Convert(c[k], s.clamped, simd::kSaturate), s.square, simd::kSaturate);
      sum = Add(Add(sq[0], sq[1], s.square, simd::kSaturate), sq[2], s.square, simd::kSaturate);
    });
  }
  Roots r;
  r.disc = Sub(Uni{s.r2}, sum, s.disc);
  Multi root;
  simd::WithExpectedSaturation(m, [&] { root = Sqrt(r.disc, s.root); });  // a miss's: unused
  r.t0 = Sub(tca, root, p.t);
  r.t1 = Add(tca, root, p.t);
  r.grazing = simd::Near(m, r.disc, s.grazeBand, p.fracBits);
  return r;
}

// One polygon along o + t·d: t (where |n·d| is not within the parallel band), whether the ray
// certainly passes inside, whether it might (the edge functions and the facing as the
// tracer's InsideAlongRay, each edge certain beyond ±edgeBand), and `parallel` (|n·d| small:
// t not computed, not certified).
struct PolygonCross {
  Multi t, inside, possible, parallel;
};

PolygonCross PolygonAlong(Machine& m, const Multi (&o)[3], const Multi (&d)[3],
                          const PolygonTerms& g, const SecondaryPlan& p) {
  const int F = p.fracBits;
  const Format wide = Format::Signed(p.intBits + 3, F);
  const Multi nd = simd::Dot3(d, g.normal, wide), no = simd::Dot3(o, g.normal, wide);
  const Multi num = Sub(Uni{g.offset}, no, wide);
  PolygonCross c;
  c.parallel = simd::Near(m, nd, p.parallelBand, F);
  c.t = Broadcast(m, Fixed{p.t, p.t.MaxRaw()});
  Where(!c.parallel, [&] {
    simd::WithExpectedSaturation(m, [&] { c.t = Div(num, nd, p.t, simd::kSaturate); });
  });
  const Multi facing = simd::Zero(m) < nd;  // s = sign(d·n) > 0
  std::vector<std::array<Multi, 3>> rel(g.vertices.size());
  for (size_t v = 0; v < g.vertices.size(); ++v)
    for (int k = 0; k < 3; ++k) rel[v][k] = Sub(Uni{g.vertices[v][k]}, o[k], p.edgeVector);
  const Multi band = Const(m, g.edgeBand, F), minusBand = Const(m, -g.edgeBand, F);
  Multi inside = simd::Zero(m), unsure = simd::Zero(m);
  for (const PolygonEdgeGroup& group : g.groups) {
    Multi in = Broadcast(m, Fixed{bitserial::BoolFormat(), 1}), out = simd::Zero(m);
    for (const PolygonEdge& e : group) {
      const auto& pa = rel[e.p];
      const auto& qa = rel[e.q];
      const Multi cross[3] = {
          Sub(Mul(pa[1], qa[2], p.edgeCross), Mul(pa[2], qa[1], p.edgeCross), p.edgeCross),
          Sub(Mul(pa[2], qa[0], p.edgeCross), Mul(pa[0], qa[2], p.edgeCross), p.edgeCross),
          Sub(Mul(pa[0], qa[1], p.edgeCross), Mul(pa[1], qa[0], p.edgeCross), p.edgeCross)};
      const Multi value = Dot(d, cross, p.edgeValue);
      // side·s·e > 0 is the inside: with side < 0 the comparisons swap.
      const Multi above = band < value, below = value < minusBand;
      const Multi& pos = e.side > 0 ? above : below;
      const Multi& neg = e.side > 0 ? below : above;
      in = in && ((facing && pos) || (!facing && neg));
      out = out || (facing && neg) || (!facing && pos);
    }
    unsure = unsure || (!in && !out);
    inside = Xor(inside, in);
  }
  c.possible = inside || unsure;
  c.inside = inside && !unsure && !c.parallel;
  return c;
}

// The first sphere along every ray: object (index + 1, 0 = none), t, and whether that is
// uncertain (a grazing or near-ε candidate that may lie in front, or two hits within their
// bounds of each other).
struct Nearest {
  Multi object, t, uncertain;
};

Nearest FindNearest(Machine& m, const Multi (&o)[3], const Multi (&d)[3], const Multi& from,
                    const Multi& outward, const SecondaryPlan& p) {
  const int F = p.fracBits;
  const Fixed tMax{p.t, p.t.MaxRaw()};
  Nearest n;
  n.t = Broadcast(m, tMax);
  n.object = Broadcast(m, Fixed{p.index, 0});
  Multi tie = simd::Zero(m), tGraze = Broadcast(m, tMax);
  const Multi eps = Const(m, p.epsilon, F), none = Broadcast(m, tMax);
  // Object i's candidate t where `hit` into the best, a near tie with the best flagged.
  auto fold = [&](const Multi& t, const Multi& hit, size_t i) {
    tie = tie || (hit && (n.t < none) && simd::Near(m, t - n.t, 2 * p.tError, F));
    const Multi closer = hit && (t < n.t);
    Where(closer, [&] {
      n.t = t;
      n.object = Broadcast(m, Fixed{p.index, int64_t(i) + 1});
    });
  };
  for (size_t i = 0; i < p.objects.size(); ++i) {
    const Multi self = from == Multi::Constant(m, Fixed{p.index, int64_t(i) + 1});
    if (!p.objects[i].sphere) {
      // A plane is met once: the polygon a ray leaves is never its next hit.
      const PolygonTerms& g = p.polygons[p.objects[i].index];
      const PolygonCross c = PolygonAlong(m, o, d, g, p);
      const Multi hit = c.inside && (eps < c.t) && !self;
      const Multi front = c.parallel || (Const(m, p.epsilon - g.tError - p.ulp, F) < c.t);
      const Multi unsure = c.possible && !self && front &&
                           (!c.inside || simd::Near(m, c.t - eps, g.tError + p.ulp, F));
      Multi low;
      simd::WithExpectedSaturation(m, [&] {
        low = Select(c.parallel, Broadcast(m, Fixed{p.t, p.t.MinRaw()}),
                     simd::SubBound(m, c.t, g.tError + p.ulp, p.t), p.t);
      });
      Where(unsure, [&] { tGraze = Min(tGraze, low, p.t); });
      fold(c.t, hit, i);
      continue;
    }
    const SphereTerms& s = p.spheres[p.objects[i].index];
    const Roots r = SphereRoots(m, o, d, s, p);
    // The sphere the ray leaves: outward, no hit; inward, its far root.
    const Multi leaving = self && outward, entering = self && !outward;
    const Multi t = Select(entering || (eps < r.t0), Select(entering, r.t1, r.t0, p.t), r.t1, p.t);
    const Multi real = simd::Zero(m) <= r.disc;
    const Multi hit = real && (eps < t) && !leaving;
    // Uncertain: grazing, or a root within its bound of ε — unless the far root is
    // certainly behind ε; on the sphere it enters, only grazing.
    const Multi nearEps = (simd::Near(m, r.t0 - eps, s.tError + p.ulp, F) ||
                           simd::Near(m, r.t1 - eps, s.tError + p.ulp, F)) &&
                          (real || r.grazing) && !self;
    const Multi front = Const(m, p.epsilon - s.slack, F) < r.t1;
    const Multi unsure = (r.grazing || nearEps) && front && !leaving;
    Where(unsure, [&] { tGraze = Min(tGraze, simd::SubBound(m, r.t0, s.slack, p.t), p.t); });
    fold(t, hit, i);
  }
  // A flagged candidate matters if it may lie in front of the best's true t <= t + E.
  Multi limit;
  simd::WithExpectedSaturation(
      m, [&] { limit = Add(n.t, Const(m, p.tError, F), p.t, simd::kSaturate); });
  n.uncertain = tie || ((tGraze <= limit) && (tGraze < none));
  return n;
}

// The light let through toward one light from every hit point P along the unit l (distance
// dist): each root in (ε, dist) multiplies by its sphere's T; `uncertain` where a root or the
// grazing band is within its bound of deciding a crossing.
// The hit's own sphere (`object`, index + 1): a shadow ray from outside (`inside` 0) cannot
// meet it again; from inside it crosses it once, at the far root.
// A shadow ray from inside its sphere leaves it exactly once when the light is outside it.
void ShadowProduct(Machine& m, const Multi (&pt)[3], const Multi (&l)[3], const Multi& dist,
                   const Multi& object, const Multi& inside, const SecondaryPlan& p, size_t light,
                   Multi& through, Multi& uncertain) {
  const int F = p.fracBits;
  through = Broadcast(m, Fixed{p.unit, int64_t(1) << F});
  uncertain = simd::Zero(m);
  const Multi eps = Const(m, p.epsilon, F);
  const Multi zero = Broadcast(m, Fixed{p.unit, 0});
  for (size_t i = 0; i < p.objects.size(); ++i) {
    const Multi self = object == Multi::Constant(m, Fixed{p.index, int64_t(i) + 1});
    if (!p.objects[i].sphere) {
      const PolygonTerms& g = p.polygons[p.objects[i].index];
      const PolygonCross c = PolygonAlong(m, pt, l, g, p);
      const Multi cross = c.inside && (eps < c.t) && (c.t < dist) && !self;
      if (g.transparency <= 0) {
        Where(cross, [&] { through = zero; });
      } else {
        const Uni kt{Tight(g.transparency, F)};
        Where(cross, [&] { through = Mul(through, kt, p.unit); });
      }
      const double band = g.tError + p.ulp;
      const Multi inRange = c.parallel || ((Const(m, p.epsilon - band, F) < c.t) &&
                                           (simd::SubBound(m, c.t, band, p.t) < dist));
      const Multi near = simd::Near(m, c.t - eps, band, F) || simd::Near(m, c.t - dist, band, F);
      uncertain = uncertain || (c.possible && !self && inRange && (!c.inside || near));
      continue;
    }
    const SphereTerms& s = p.spheres[p.objects[i].index];
    const Roots r = SphereRoots(m, pt, l, s, p);
    const Multi real = simd::Zero(m) <= r.disc;
    const Multi cross0 = real && (eps < r.t0) && (r.t0 < dist) && !self;
    const Multi exits =
        inside && Broadcast(m, Fixed{bitserial::BoolFormat(), s.lightOutside[light] ? 1 : 0});
    const Multi cross1 = (real && (eps < r.t1) && (r.t1 < dist) && !self) || (self && exits);
    if (s.transparency <= 0) {
      Where(cross0 || cross1, [&] { through = zero; });
    } else {
      const Uni kt{Tight(s.transparency, F)};
      Where(cross0, [&] { through = Mul(through, kt, p.unit); });
      Where(cross1, [&] { through = Mul(through, kt, p.unit); });
    }
    const double band = s.tError + p.ulp;
    const Multi near = simd::Near(m, r.t0 - eps, band, F) || simd::Near(m, r.t1 - eps, band, F) ||
                       simd::Near(m, r.t0 - dist, band, F) || simd::Near(m, r.t1 - dist, band, F);
    const Multi inRange =
        (Const(m, p.epsilon - s.slack, F) < r.t1) && (simd::SubBound(m, r.t0, s.slack, p.t) < dist);
    const Multi unsure = (r.grazing || (near && (real || r.grazing) && !self)) && inRange;
    uncertain = uncertain || (unsure && !self);
  }
}

// The whole program; read = false runs it for its allocation only (BounceFits).
void Run(Machine& m, const SecondaryPlan& p, bool intersect, const BounceInputs& in,
         BounceOutputs* out, bool audit) {
  const int F = p.fracBits;
  Multi o[3], d[3];
  for (int k = 0; k < 3; ++k)
    o[k] = Loaded(m, p.coord, in.o[k]), d[k] = Loaded(m, p.direction, in.d[k]);
  auto flags = [&](const std::vector<uint8_t>& v) {
    return Loaded(m, bitserial::BoolFormat(), std::vector<int64_t>(v.begin(), v.end()));
  };
  const Multi live = flags(in.live), outward = flags(in.outward);
  const Multi from = Loaded(m, p.index, in.from);
  Multi object, t, uncertain;
  if (!intersect) {
    object = Loaded(m, p.index, in.object), t = Loaded(m, p.t, in.t);
  }
  // The inputs are already on the array (the previous bounce or the primary pass wrote
  // them; the compaction's moves are charged apart): the program starts here.
  m.Report().Clear();
  m.ClearFlags();
  if (intersect) {
    bitserial::WhereScope scope(live);
    Normalise(d, p);
    Nearest n = FindNearest(m, o, d, from, outward, p);
    object = std::move(n.object), t = std::move(n.t), uncertain = std::move(n.uncertain);
  } else {
    uncertain = simd::Zero(m);
  }
  const Multi hit = live && (Broadcast(m, Fixed{p.index, 0}) < object);
  const size_t lights = p.lights[0].size();
  Multi pt[3], normal[3], mirror[3], refracted[3], tir = simd::Zero(m), inside;
  std::vector<Multi> nl(lights), rv(lights), through(lights), shadowUnsure(lights);
  {
    bitserial::WhereScope scope(hit);
    for (int k = 0; k < 3; ++k) pt[k] = Add(o[k], Mul(t, d[k], p.t), p.coord);
    // The unit normal (P − c)/r of the sphere hit, normalised, turned to face the ray.
    for (int k = 0; k < 3; ++k) normal[k] = Multi(m, p.direction, "normal");
    for (size_t i = 0; i < p.objects.size(); ++i) {
      bitserial::WhereScope one(object == Multi::Constant(m, Fixed{p.index, int64_t(i) + 1}));
      if (!p.objects[i].sphere) {  // the polygon's front normal
        const PolygonTerms& g = p.polygons[p.objects[i].index];
        for (int k = 0; k < 3; ++k) normal[k] = Broadcast(m, g.normal[k]);
        continue;
      }
      const SphereTerms& s = p.spheres[p.objects[i].index];
      for (int k = 0; k < 3; ++k)
        normal[k] = Mul(Sub(pt[k], Uni{s.centre[k]}, p.offset), Uni{s.inverseRadius}, p.direction,
                        simd::kSaturate);
    }
    Normalise(normal, p);
    Multi dn = Dot(d, normal, p.direction);
    inside = simd::Zero(m) < dn;
    Where(inside, [&] {
      for (int k = 0; k < 3; ++k) normal[k] = Neg(normal[k], p.direction);
      dn = Neg(dn, p.direction);
    });
    for (int k = 0; k < 3; ++k) {
      const Multi twice = Mul(dn, normal[k], p.t);
      mirror[k] = Sub(d[k], Add(twice, twice, p.t), p.direction, simd::kSaturate);
    }
    if (p.anyTransparent) {
      // Snell (hosts/trace/tracer.h Refract): eta = ior leaving, 1/ior entering.
      Multi eta = Const(m, 1, F);
      for (size_t i = 0; i < p.objects.size(); ++i) {
        const ObjectTerms& ob = p.objects[i];
        const double t =
            ob.sphere ? p.spheres[ob.index].transparency : p.polygons[ob.index].transparency;
        const double ior = ob.sphere ? p.spheres[ob.index].ior : p.polygons[ob.index].ior;
        if (t <= 0) continue;
        const Multi one = object == Multi::Constant(m, Fixed{p.index, int64_t(i) + 1});
        Where(one && inside, [&] { eta = Const(m, ior, F); });
        Where(one && !inside, [&] { eta = Const(m, 1 / ior, F); });
      }
      const Multi cosi = Neg(dn, Format::Signed(2, F));
      const Multi sin2 =
          Sub(Const(m, 1, F), Square(cosi, Format::Unsigned(2, F)), Format::Signed(2, F));
      const Format wide = Format::Signed(2 * p.eta.intBits + 2, F);
      const Multi k = Sub(Const(m, 1, F), Mul(Square(eta, wide), sin2, wide), wide);
      tir = k < simd::Zero(m);
      Multi root;
      simd::WithExpectedSaturation(
          m, [&] { root = Sqrt(k, Format::Unsigned(2 * p.eta.intBits + 2, F)); });
      const Format term = Format::Signed(p.eta.intBits + 2, F);
      const Multi coef = Sub(Mul(eta, cosi, term), root, term);
      for (int c = 0; c < 3; ++c)
        refracted[c] =
            Add(Mul(eta, d[c], term), Mul(coef, normal[c], term), p.direction, simd::kSaturate);
      for (int c = 0; c < 3; ++c) Where(tir, [&] { refracted[c] = mirror[c]; });
      Normalise(refracted, p);
    }
    // Each light: the unit direction l, N·L, R·(−D) = l·d − 2(N·L)(N·d), the shadow product.
    for (size_t j = 0; j < lights; ++j) {
      Multi w[3], l[3];
      for (int k = 0; k < 3; ++k) w[k] = Sub(Uni{p.lights[k][j]}, pt[k], p.toLight);
      const Multi dist =
          Sqrt(simd::SumOfSquares(w, Format::Unsigned(2 * p.toLight.intBits, F)), p.distance);
      for (int k = 0; k < 3; ++k) l[k] = Div(w[k], dist, p.direction, simd::kSaturate);
      nl[j] = Dot(normal, l, p.direction);
      const Multi twice = Mul(nl[j], dn, p.direction);
      rv[j] = Sub(Dot(l, d, p.direction), Add(twice, twice, Format::Signed(2, F)),
                  Format::Signed(3, F), simd::kSaturate);
      ShadowProduct(m, pt, l, dist, object, inside, p, j, through[j], shadowUnsure[j]);
    }
  }
  // Overflow anywhere in a ray's program (its flags latch per PE) makes it uncertain.
  if (!out) return;
  const int64_t n = m.VirtualPes();
  auto read = [&](const Multi& x, std::vector<int64_t>& to) {
    to = x.ReadRaw();
    out->hostLinkBits += int64_t(x.Width()) * n;
  };
  auto readFlags = [&](const Multi& x, std::vector<uint8_t>& to) {
    std::vector<int64_t> raw;
    read(x, raw);
    to.assign(raw.begin(), raw.end());
  };
  // The emulation's copy of what stays on the array (not charged: the next bounce reads it
  // where it is).
  auto peek = [&](const Multi& x, std::vector<int64_t>& to) {
    const int w = x.Width();
    to.assign(n, 0);
    for (int i = 0; i < w; ++i)
      for (int64_t pe = 0; pe < n; ++pe)
        if (x.BitAt(i, pe)) to[pe] |= int64_t{1} << i;
    if (x.Format().isSigned)
      for (int64_t& v : to)
        if ((v >> (w - 1)) & 1) v -= int64_t{1} << w;
  };
  read(object, out->object);
  m.Charge("hostRead", bitserial::HostTransferCost(1));  // the overflow flags
  readFlags(uncertain, out->uncertain);
  for (int64_t pe = 0; pe < n; ++pe)
    if (m.Overflow(pe) || m.DivideByZero(pe)) out->uncertain[pe] = 1;
  readFlags(tir, out->tir);
  out->nl.resize(lights), out->rv.resize(lights), out->through.resize(lights);
  out->shadowUncertain.resize(lights);
  bool anyShadowUnsure = false;
  for (size_t j = 0; j < lights; ++j) {
    read(nl[j], out->nl[j]), read(rv[j], out->rv[j]), read(through[j], out->through[j]);
    readFlags(shadowUnsure[j], out->shadowUncertain[j]);
    anyShadowUnsure |= std::find(out->shadowUncertain[j].begin(), out->shadowUncertain[j].end(),
                                 1) != out->shadowUncertain[j].end();
  }
  bool anyUnsure = false;
  for (int64_t pe = 0; pe < n; ++pe) anyUnsure |= in.live[pe] && out->uncertain[pe];
  if (audit)
    for (int k = 0; k < 3; ++k) peek(o[k], out->audit.o[k]), peek(d[k], out->audit.d[k]);
  {
    std::vector<int64_t> raw;
    peek(inside, raw);
    out->inside.assign(raw.begin(), raw.end());
  }
  for (int k = 0; k < 3; ++k) {
    if (anyUnsure) read(o[k], out->o[k]), read(d[k], out->d[k]);
    if (anyShadowUnsure)
      read(pt[k], out->p[k]);
    else
      peek(pt[k], out->p[k]);
    peek(mirror[k], out->mirror[k]);
    if (p.anyTransparent) peek(refracted[k], out->refracted[k]);
  }
}

}  // namespace

void RunBounce(Machine& m, const SecondaryPlan& plan, bool intersect, const BounceInputs& in,
               BounceOutputs& out, bool audit) {
  Run(m, plan, intersect, in, &out, audit);
}

bool BounceFits(const bitserial::MachineProfile& profile, int layers, const SecondaryPlan& plan,
                bool intersect) {
  bitserial::MachineProfile one = profile;
  one.physicalPes = 512;
  one.shapes = {bitserial::MeshShape{{64, 8}}};
  one.internalBitsPerPe /= layers;
  one.externalBitsPerPe /= layers;
  BounceInputs in;
  for (int k = 0; k < 3; ++k) in.o[k].assign(1, 0), in.d[k].assign(1, 0);
  in.object.assign(1, 0), in.t.assign(1, 0), in.from.assign(1, 0);
  in.live.assign(1, 0), in.outward.assign(1, 0);
  try {
    Machine m(one, 1);
    Run(m, plan, intersect, in, nullptr, false);
    return true;
  } catch (const UserError&) {
    return false;
  }
}

}  // namespace zephyr::wavefront
