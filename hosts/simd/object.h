// hosts/simd/object.h — one object of the SIMD primary pass: its host set-up and array
// program (docs/simd.md, "The program" and "Error bounds"). Internal to hosts/simd/.
//
// Every primitive is reduced on the host to `uni` constants (the eye and T⁻¹ folded in) and
// tested on the array against the multi direction d (s1.Fd, the double unit direction
// rounded to nearest). Each kind's file derives, from the formats, sound bounds on the error
// of every quantity (ObjectBounds) beside the array program those bounds are about; the
// program gives per PE a candidate t, whether it is a hit, and whether the decision is
// uncertain (within the bounds of a boundary: grazing, the rim of a polygon, hither)
// together with a lower bound on where the true hit could be.
#pragma once

#include <memory>
#include <utility>

#include "bitserial/float.h"
#include "bitserial/multi.h"
#include "hosts/simd/audit.h"
#include "hosts/simd/plan.h"

namespace zephyr::simd {

// One object's answer on the array (all multis over every PE).
struct Candidate {
  bitserial::Multi t;          // in the pass's t format; meaningful where hit or uncertain
  bitserial::Multi hit;        // 1 bit: a hit beyond hither at t
  bitserial::Multi uncertain;  // 1 bit: the hit/miss or hither decision is within the bounds
  bitserial::Multi tLow;       // in the t format: where uncertain, the true hit (if any) is >= tLow
  // Optional, per PE where hit and not uncertain: a margin with |t − t_exact| <= lowMargin,
  // at most the object's bounds.tError + 2^-F rounded up to the F-bit grid (so below
  // tError + 2·2^-F; an unsigned format with F fraction bits). Empty: tError + 2^-F rounded
  // to nearest, everywhere. A cone's error depends on its divisor and discriminant per PE
  // (hosts/simd/cone.cpp, docs/simd.md "Error bounds", cones).
  bitserial::Multi lowMargin;
};

// The ray directions on the array: fixed point (s1.Fd, the matrix's) always; with --number
// float also in the pass's float format (each the double unit direction rounded to nearest).
struct Directions {
  bitserial::Multi fixed[3];
  bitserial::MultiFloat floats[3];  // empty with --number fixed
};

// An object's array program with its host set-up (constants and formats) built once by the
// planner.
class ObjectProgram {
 public:
  virtual ~ObjectProgram() = default;
  // Runs the program against the directions d (every PE). With an `audit` (tests only,
  // hosts/simd/audit.h) it also records each quantity it computes with the bound it claims;
  // the pass gives none (nullptr), and the program's operations do not depend on it.
  virtual Candidate Run(bitserial::Machine& m, const Directions& d, Audit* audit) const = 0;
};

// The plan of one object from its program (a kind's class with Bounds() and Formats()).
template <typename Program, typename... Args>
ObjectPlan PlanOf(Args&&... args) {
  auto program = std::make_shared<Program>(std::forward<Args>(args)...);
  ObjectPlan plan;
  plan.bounds = program->Bounds();
  plan.formats = program->Formats();
  plan.program = std::move(program);
  return plan;
}

// What the planner needs of an object before it chooses the formats: its farthest point from
// the eye and its smallest feature (a sphere's radius, an ellipsoid's smallest semi-axis, a
// polygon's shortest edge / 2, a cone's smaller of radius and height / 2); scene units.
struct ObjectExtent {
  double farthest = 0, feature = 1e300;
};

// Per kind (hosts/simd/<kind>.cpp): the extent, and the plan at the pass's formats.
ObjectExtent SphereExtent(const Primitive& p, const Vec3& eye);
ObjectPlan PlanSphere(const Primitive& p, const Vec3& eye, const PassFormats& pf);
// The sphere in bit-serial float (pf.floatFormat; hosts/simd/sphere_float.cpp).
ObjectPlan PlanFloatSphere(const Primitive& p, const Vec3& eye, const PassFormats& pf);
ObjectExtent EllipsoidExtent(const Primitive& p, const Vec3& eye);
ObjectPlan PlanEllipsoid(const Primitive& p, const Vec3& eye, const PassFormats& pf);
ObjectExtent PolygonExtent(const Primitive& p, const Vec3& eye);
// planeOf: the polygon in exactly p's plane whose plane constants t is computed from (p itself
// unless exact::CoplanarPolygons names another), so one plane's polygons share t bit for bit.
ObjectPlan PlanPolygon(const Primitive& p, const Vec3& eye, const PassFormats& pf,
                       const Primitive& planeOf);
ObjectExtent ConeExtent(const Primitive& p, const Vec3& eye);
ObjectPlan PlanCone(const Primitive& p, const Vec3& eye, const PassFormats& pf);

// The linear part of T⁻¹ (world -> object) as rows, the object-space eye and ‖T_lin‖_F
// (shared by the ellipsoid and the cone).
struct ObjectFrame {
  double a[3][3];
  Vec3 eye;
  double forwardNorm = 1;  // ‖T's linear part‖_F (>= σ_max of T, so σ_min(T⁻¹) >= 1/this)
  double rowSum[3] = {};   // Σ_j |T⁻¹_kj|: |d'_k| <= this for |d_j| <= 1
  double ddMax = 0;        // Σ_k rowSum_k² >= |d'|²: the formats of d' and |d'|²
};
ObjectFrame MakeObjectFrame(const Primitive& p, const Vec3& eye);

// ‖T⁻¹‖_F (1 without a transform): a world length is at least the object length / this.
double InverseFrobenius(const Primitive& p);

}  // namespace zephyr::simd
