// hosts/simd/polygon.cpp — a polygon on the array: signs of edge functions ĝ·d (one linear
// form of the direction per edge) and the plane's t = dist/(n̂·d), with their error bounds
// (docs/simd.md, "The program", "Error bounds").
//
// An affine map keeps a polygon planar, so T⁻¹ folds into the host's constants:
// g·(T⁻¹d) = (T⁻ᵀg)·d; the polygon is taken to world space once.
#include <fmt/format.h>

#include <array>
#include <cmath>

#include "hosts/simd/object.h"
#include "hosts/simd/ops.h"
#include "hosts/trace/intersect.h"

namespace zephyr::simd {

using bitserial::Machine;
using bitserial::Multi;
using fixed::Fixed;
using fixed::Format;

namespace {

// One edge function on the array: e = ĝ·d with ĝ = normalize((p − eye) × (q − eye)) for the
// edge's ends in the canonical order of hosts/trace/intersect.h, so two polygons sharing
// the edge compute the same e bit for bit. The group's inside is e >= 0 where `owned`, else
// e < 0: the tracer's shared-edge rule (InsideAlongRay), so a ray through the edge is inside
// exactly one of the two faces and no crack opens between them.
struct EdgeFunction {
  Vec3 g;
  bool owned = true;
};

// A polygon in world space, its unit normal and the eye's signed distance.
struct WorldPolygon {
  std::vector<Vec3> v;
  Vec3 normal;
  double eyeDistance = 0;  // n̂·(v0 − eye)
  // Edge groups (PolygonEdgeGroups: a convex polygon is one group, a concave one a fan of
  // triangles, even-odd = parity): inside a group iff every edge function says inside.
  std::vector<std::vector<EdgeFunction>> groups;
  bool degenerate = false;
};

WorldPolygon MakeWorldPolygon(const Primitive& p, const Vec3& eye) {
  WorldPolygon w;
  WorldSpacePolygon world = ToWorldSpace(p);
  w.v = std::move(world.vertices);
  w.normal = world.normal;
  w.eyeDistance = Dot(w.normal, w.v[0] - eye);
  // A ray from the eye that meets the plane in front has sign(n̂·d) = σ, the facing the
  // tracer's rule uses.
  const int sigma = w.eyeDistance >= 0 ? 1 : -1;
  for (const PolygonEdgeGroup& group : PolygonEdgeGroups(w.v, w.normal)) {
    std::vector<EdgeFunction> g;
    for (const PolygonEdge& e : group) {
      const Vec3 c = Cross(w.v[e.p] - eye, w.v[e.q] - eye);
      const double len = Length(c);
      if (!(len > 1e-300)) w.degenerate = true;  // the eye on the edge's line
      g.push_back({len > 1e-300 ? c / len : Vec3{}, e.side * sigma > 0});
    }
    w.groups.push_back(g);
  }
  if (w.groups.empty()) w.degenerate = true;
  return w;
}

class PolygonProgram final : public ObjectProgram {
 public:
  // planeOf: the polygon whose plane constants t is computed from (the lowest-index polygon
  // in exactly the same plane, exact::CoplanarPolygons), so that polygons in one plane compute
  // the same t bit for bit; the edges are always p's own.
  PolygonProgram(const Primitive& p, const Vec3& eye, const PassFormats& pf,
                 const Primitive& planeOf)
      : pf_(pf), w_(MakeWorldPolygon(p, eye)) {
    if (&planeOf != &p) {
      const WorldPolygon plane = MakeWorldPolygon(planeOf, eye);
      w_.normal = plane.normal, w_.eyeDistance = plane.eyeDistance;
    }
    Bound(eye);
  }

  const ObjectBounds& Bounds() const { return b_; }

  std::vector<PlannedFormat> Formats() const {
    size_t edges = 0;
    for (const auto& g : w_.groups) edges += g.size();
    return {
        {"edge functions ĝ·d, n̂·d", Format::Signed(1, pf_.fracBits),
         fmt::format("{} unit edge normal(s), unit plane normal (T folded in on the host)", edges)},
        {"t = dist/(n̂·d)", pf_.t, "by division"}};
  }

  Candidate Run(Machine& m, const Directions& dirs, Audit* audit) const override {
    const Multi(&d)[3] = dirs.fixed;
    const int F = pf_.fracBits;
    const Format unit = Format::Signed(1, F);
    // Inside: parity over the groups of (every edge function on its inside: e >= 0 for an
    // owned edge, e < 0 for the other side); each edge function is a linear form in d with
    // uni coefficients. Uncertain: some group neither clearly inside (every e beyond the
    // band on its inside) nor clearly outside (one beyond the band on its outside).
    const Multi band = Broadcast(m, Tight(b_.grazeBand, F)), zero = Zero(m);
    const Multi negBand = Broadcast(m, fixed::Neg(Tight(b_.grazeBand, F), Format::Signed(1, F)));
    Multi inside, edgeUncertain;
    const int64_t pes = m.VirtualPes();
    for (size_t gi = 0; gi < w_.groups.size(); ++gi) {
      const std::vector<EdgeFunction>& group = w_.groups[gi];
      Multi in, clearIn, clearOut;
      for (size_t k = 0; k < group.size(); ++k) {
        const EdgeFunction& g = group[k];
        const Fixed cc[3] = {Tight(g.g.x, F), Tight(g.g.y, F), Tight(g.g.z, F)};
        const Multi e = Dot3(d, cc, unit);
        // The audit (hosts/simd/audit.h): each edge function within e_E of the exact ĝ·d̂.
        if (audit)
          audit->Record("edge " + std::to_string(gi) + "." + std::to_string(k), e,
                        Audit::Where({}, b_.grazeBand, pes));
        Multi pos = g.owned ? (zero <= e) : (e < zero);
        Multi posClear = g.owned ? (band < e) : (e < negBand);
        Multi negClear = g.owned ? (e < negBand) : (band < e);
        in = in.Empty() ? pos : (in && pos);
        clearIn = clearIn.Empty() ? posClear : (clearIn && posClear);
        clearOut = clearOut.Empty() ? negClear : (clearOut || negClear);
      }
      const Multi unsure = !(clearIn || clearOut);
      inside = inside.Empty() ? in : Xor(inside, in);
      edgeUncertain = edgeUncertain.Empty() ? unsure : (edgeUncertain || unsure);
    }
    if (w_.groups.empty()) inside = zero, edgeUncertain = !zero;  // degenerate: always flagged
    // The plane: t = |n̂·(v0 − eye)| / (σ n̂·d), in front where the denominator is positive.
    const double sigma = w_.eyeDistance >= 0 ? 1 : -1;
    const Vec3 n = w_.normal * sigma;
    const Fixed ncc[3] = {Tight(n.x, F), Tight(n.y, F), Tight(n.z, F)};
    const Multi den = Dot3(d, ncc, unit);
    const Multi num = Broadcast(m, Tight(std::abs(w_.eyeDistance), F));
    Candidate out;
    const Multi front = zero < den;
    const Multi cand = front && (inside || edgeUncertain);
    Where(cand, [&] { out.t = Div(num, den, pf_.t, kSaturate); });
    const Multi hither = Broadcast(m, Tight(pf_.hither, F));
    out.hit = cand && inside && (hither < out.t);
    const Multi nearHither = b_.alwaysUncertain ? Broadcast(m, Fixed{Format::Unsigned(1, 0), 1})
                                                : Near(m, out.t - hither, b_.tError + pf_.Ulp(), F);
    out.uncertain = cand && (edgeUncertain || nearHither);
    out.tLow = SubBound(m, out.t, b_.slack, pf_.t);
    if (audit) Record(*audit, den, out);
    return out;
  }

 private:
  // The audit's record (hosts/simd/audit.h): the denominator σn̂·d within e_E everywhere, a
  // certain hit's t within tError, an uncertain candidate's t >= the true hit − slack (edge
  // functions are recorded as Run computes them). Nothing where the bounds do not close.
  void Record(Audit& audit, const Multi& den, const Candidate& out) const {
    if (b_.alwaysUncertain) return;
    const int64_t n = den.GetMachine().VirtualPes();
    const std::vector<double> hit = Audit::Values(out.hit), unsure = Audit::Values(out.uncertain);
    std::vector<double> eT(n, Audit::kNoClaim), slack(n, Audit::kNoClaim);
    for (int64_t pe = 0; pe < n; ++pe) {
      if (hit[pe] && !unsure[pe]) eT[pe] = b_.tError;
      if (unsure[pe]) slack[pe] = b_.slack;
    }
    audit.Record("den", den, Audit::Where({}, b_.grazeBand, n));
    audit.Record("t", out.t, eT);
    audit.Record("t - slack", out.t, slack, Audit::Side::kAbove);
  }

  // The bounds: every ĝ·d and n̂·d is a unit constant (rounded to nearest) times d; the
  // division's error from n̂·d >= |dist|/farthest − eE for any ray that reaches the polygon.
  void Bound(const Vec3& eye) {
    const double u = pf_.Ulp(), dd = pf_.DirError();
    b_.kind = ShapeKind::kPolygon;
    for (const Vec3& v : w_.v) b_.farthest = std::max(b_.farthest, Length(v - eye));
    b_.intBits = IntBitsFor(b_.farthest) + 1;
    const double eE = std::sqrt(3.0) * dd + 1.5 * u * (1 + dd) + 3 * u;
    b_.grazeBand = eE;
    const double n = std::abs(w_.eyeDistance);
    const double denMin = n / b_.farthest - eE;
    if (w_.degenerate || !(denMin > 0)) {
      b_.alwaysUncertain = true;
      b_.tError = b_.slack = kInf;
      return;
    }
    b_.tError = b_.farthest * eE / denMin + (u / 2) / denMin + u;
    b_.slack = b_.tError + u;
  }

  PassFormats pf_;
  WorldPolygon w_;
  ObjectBounds b_;
};

}  // namespace

ObjectExtent PolygonExtent(const Primitive& p, const Vec3& eye) {
  ObjectExtent e;
  const std::vector<Vec3> v = ToWorldSpace(p).vertices;
  for (size_t k = 0; k < v.size(); ++k) {
    e.farthest = std::max(e.farthest, Length(v[k] - eye));
    e.feature = std::min(e.feature, Length(v[k] - v[(k + 1) % v.size()]) / 2);
  }
  return e;
}

ObjectPlan PlanPolygon(const Primitive& p, const Vec3& eye, const PassFormats& pf,
                       const Primitive& planeOf) {
  return PlanOf<PolygonProgram>(p, eye, pf, planeOf);
}

}  // namespace zephyr::simd
