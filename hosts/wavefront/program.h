// hosts/wavefront/program.h — the array program of one wavefront bounce (docs/wavefront.md,
// "The bounce program"), and its formats and error bounds planned per scene. Internal to
// hosts/wavefront/: wavefront.cpp runs it pass by pass.
//
// A bounce runs on the live rays of one ray-tree level, each in one virtual PE: its origin o
// and direction d are multis (the primary pass's eye is a uni; here every term is multi).
// With `intersect` it finds each ray's first sphere (Hearn–Baker through the cross product,
// f = c − o per PE); then, where a ray hit, the hit point, the unit normal turned to face the
// ray, the mirror and the Snell directions (total internal reflection flagged), and per light
// the shadow ray's transparent-shadow product with N·L and R·(−D) for the host's local term.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "bitserial/machine.h"
#include "fixed/format.h"
#include "hosts/scene/scene.h"
#include "hosts/simd/bounds.h"
#include "hosts/trace/intersect.h"

namespace zephyr::wavefront {

// An ellipsoid's object space (a transformed sphere, docs/wavefront.md "Ellipsoids"): the ray
// o' = M(o − anchor), d' = M·d with M = T⁻¹'s linear part (uni constants rounded to nearest),
// at Fl > F fraction bits, so t is the world t; the sphere is centred at the object-space origin.
// Normals map by Mᵀ.
struct EllipsoidTerms {
  fixed::Fixed anchor[3];      // the world centre
  fixed::Fixed inverse[3][3];  // M
  fixed::Format local[3];      // o'_k (|o'_k| <= Σ_j |M_kj|·|o_j − anchor_j|)
  fixed::Format dLocal[3];     // d'_k (|d'_k| <= Σ_j |M_kj|·(1 + δ))
  fixed::Format products;      // f·d', f×d' (f = −o')
  fixed::Format dd;            // |d'|²
  fixed::Format numerator;     // f·d' ∓ √disc
  fixed::Format offset;        // o − anchor
  int fracBits = 0;            // Fl: the object space's fraction bits (more than F)
};

// One sphere's constants and bounds on the array (scene units). A transformed sphere (an
// ellipsoid) carries its object space; its discriminant is r²|d'|² − |o'×d'|² and its roots
// (f·d' ∓ √disc)/|d'|², as the primary pass's ellipsoid (docs/simd.md).
struct SphereTerms {
  fixed::Fixed centre[3], r2, inverseRadius;
  std::optional<EllipsoidTerms> ellipsoid;
  fixed::Fixed normalScale[3][3];  // an ellipsoid's normal Mᵀ·o' scaled to length <= 1: [j][k]
  int normalInverseBits = 1;       // 1/|that| < 2^this
  fixed::Format clamped, square, disc, root;  // the cross clamp and what follows it
  double grazeBand = 0;                       // G: |disc| < G is grazing
  double tError = 0;                          // |t − t_exact| of a certain root
  double slack = 0;                           // a grazing ray's true root is >= t0 − slack
  double transparency = 0;                    // the material's T (the shadow product's factor)
  double ior = 1;
  std::vector<bool> lightOutside;  // per light: the light is outside the sphere
};

// The |n·d| thresholds of a polygon's t-error rungs (PolygonTerms::tErrorRung; the first is
// SecondaryPlan::parallelBand).
inline constexpr double kPolygonRungs[3] = {1.0 / 32, 1.0 / 8, 1.0 / 2};

// One flat polygon's constants and bounds (world space: a transformed polygon's vertices are
// mapped on the host, as the tracer does). Its inside is the tracer's: edge functions
// e = d·((p − o) × (q − o)) per edge in canonical order, by groups with the even-odd rule
// (hosts/trace/intersect.h PolygonEdgeGroups), each e certain beyond ±edgeBand.
struct PolygonTerms {
  fixed::Fixed normal[3];  // the unit front normal (Newell's, turned by a mirroring transform)
  fixed::Fixed offset;     // normal·v0
  std::vector<std::array<fixed::Fixed, 3>> vertices;
  std::vector<PolygonEdgeGroup> groups;
  // A polygon patch (NFF `pp`): per fan triangle (0, i, i+1) the barycentric weights of a
  // point P as linear forms v = α·(P − v0), w = β·(P − v0) (the tracer's Barycentric with its
  // constant denominators folded in), and the world vertex normals; empty for a flat polygon.
  struct FanTriangle {
    fixed::Fixed alpha[3], beta[3];
    int i = 0;  // the triangle (0, i, i+1)
  };
  std::vector<FanTriangle> fan;
  std::vector<std::array<fixed::Fixed, 3>> vertexNormals;
  fixed::Format weight;  // u, v, w (|·| <= the largest of 1 + Σ|α|·D, Σ|β|·D)
  double edgeBand = 0;   // |e| below it: which side the ray passes is uncertain
  double tError = 0;     // |t − t_exact| of a certain hit with |n·d| >= the plan's parallelBand
  // The same where |n·d| >= kPolygonRungs[k] (k = 0: tError): each ray takes the tightest
  // rung its |n·d| reaches (masked broadcasts), for its ties and its ε margin.
  double tErrorRung[3] = {};
  double transparency = 0, ior = 1;
};

// An open truncated cone or cylinder (NFF `c`, plain or transformed; docs/wavefront.md
// "Cones") in a local frame where its axis is z and its base the origin: x_L = frame·(x − anchor)
// with frame = R·T⁻¹'s linear part (R a rotation taking the axis to z) and anchor the world
// base, so t is the world t. With ρ = r0 + σ·o_z (σ = (r1 − r0)/h):
//   A = d_x² + d_y² − (σd_z)²,  β = o_x d_x + o_y d_y − ρ·σd_z,  C = o_x² + o_y² − ρ²,
//   disc = β² − AC = (ρd_x − σd_z o_x)² + (ρd_y − σd_z o_y)² − (d_x o_y − d_y o_x)²,
// Q = |β| + √disc, the roots −sgn(β)·Q/A and −sgn(β)·C/Q, each a hit where its height
// s = o_z + t·d_z lies in [0, h]. Everything at Fl = F + kConeExtraBits fraction bits.
struct ConeTerms {
  fixed::Fixed anchor[3], frame[3][3];  // frame at Fl + 4 fraction bits
  fixed::Fixed r0, sigma, height;
  fixed::Fixed normalScale[3][3];  // frameᵀ / (r_max·√(1 + σ²)·‖frame‖_F): [j][k]
  int normalInverseBits = 1;       // 1/|frameᵀ·n_L| scaled < 2^this
  int fracBits = 0;                // Fl
  fixed::Format offset, local[3], dLocal[3];
  fixed::Format rho, sigmaDz, a, beta, c, g, cross, square, disc, root, q, s;
  simd::ConeDivision divA, divC;                // t = Q/A (D* the parallel threshold), t = C/Q
  simd::ConeDivision divAGrazing, divCGrazing;  // the same where |disc| < G
  double grazeBand = 0;                         // G: |disc| < G is grazing
  double heightError[2][2] = {};  // |s − s_exact| of a certified root: [grazing][root]
  double tError = 0;              // |t − t_exact| of a certified root
  double tFar = 0;                // no hit of the scene is farther along a ray
  double transparency = 0, ior = 1;
};

// An object of the scene in the plan, in scene order: its kind and its index in the kind's list.
struct ObjectTerms {
  bool sphere = true;
  int index = 0;
  bool cone = false;  // then `index` is in SecondaryPlan::cones (and `sphere` is false)
};

// The formats and bounds every bounce shares (planned once per scene).
struct SecondaryPlan {
  int fracBits = 0, intBits = 0;
  double ulp = 0;             // 2^-F
  fixed::Format coord;        // s<I>.F: origins and hit points (|x|∞ <= the scene's extent)
  fixed::Format offset;       // s<I+1>.F: f = c − o
  fixed::Format t;            // s<I+2>.F: t, f·d, the cross products before their clamp
  fixed::Format direction;    // s1.F: unit directions and normals
  fixed::Format toLight;      // s<IL>.F: L − P
  fixed::Format distance;     // u<IL>.F: |L − P|
  fixed::Format eta;          // u<IE>.F: the relative index of refraction
  fixed::Format index;        // u<k>.0: object index + 1 (0 = none)
  fixed::Format unit;         // u1.F: transmissions
  double tError = 0;          // the largest sphere's tError (near ties: |t_i − t_j| < 2·tError)
  double epsilon = 0;         // the array's rays ignore roots at or below it (scene units)
  double pointSlack = 0;      // a hit point's error beyond its t's: D·δ + 2·2^-F (HostOffset)
  double directionError = 0;  // | |d|² − 1 | of a direction normalised on the array
  bool anyMirror = false, anyTransparent = false;
  std::vector<SphereTerms> spheres;
  std::vector<PolygonTerms> polygons;
  std::vector<ConeTerms> cones;
  std::vector<ObjectTerms> objects;  // every object of the scene, in order
  int normalInverseBits = 1;  // a normal's 1/|n| before normalising < 2^this (ellipsoids, patches)
  double parallelBand = 1.0 / 32;       // |n·d| below it: a polygon's t is not certified
  fixed::Format error;                  // u<k>.F: a ray's t error + ulp, and the sum of two
  fixed::Format edgeVector;             // s<I+2>.F: a vertex − o
  fixed::Format edgeCross;              // s<2I+5>.F: (p − o) × (q − o)
  fixed::Format edgeValue;              // s<2I+7>.F: d · that
  std::vector<fixed::Fixed> lights[3];  // light positions, per axis
  double primaryTError = 0;             // the primary pass's bound on t (bounce 1's hits)
  // Per scene object, the primary pass's bound on t of a hit on it (empty: primaryTError for
  // all): its plan's own, or the refine pass's where that is larger; 0 for an object whose
  // every candidate was flagged (recomputed in double on the host).
  std::vector<double> primaryErrors;
};

// The t error of a certain hit on object `object` (scene index) of ray level `bounce` along the
// unit direction `d`: the primary pass's bound at bounce 1; else the object's, a polygon's at
// the tightest rung its |n·d| reaches (with a margin for the host's double of the array's d).
double HitError(const SecondaryPlan& plan, int bounce, int object, const Vec3& d);

// The host's tMin for a ray or shadow ray it traces instead of the array, from a point whose
// hit had t error `hitError`: four times the point's distance from its surface, 1.01·E + D·δ
// + 2·2^-F (the host's tracer has no rule for the surface a ray leaves).
double HostOffset(const SecondaryPlan& plan, double hitError);

// UserError naming the object's file:line for an ellipsoid too thin for F or a cone whose
// discriminant would not fit the engine; fracBits: F (8..40); primaryTError: the primary plan's
// bound on t.
SecondaryPlan PlanSecondary(const Scene& scene, int fracBits, double primaryTError);

// One pass's rays, per virtual PE of the pass (raw two's-complement values of the plan's
// formats): origin (coord), direction (direction; need not be unit when `intersect`), and
// for a bounce without `intersect` (bounce 1: the primary pass found the hits) the object
// index + 1 and t. `live` marks the PEs holding a ray.
// `from` is the object the ray leaves (index + 1; 0 for the eye) and `outward` whether it
// leaves it outward: a sphere is convex, so an outward ray cannot meet it again and an inward
// one meets it at its far root (docs/wavefront.md, "The surface a ray leaves").
struct BounceInputs {
  std::vector<int64_t> o[3], d[3], object, t, from;
  std::vector<uint8_t> live, outward;
};

// What a pass gives per virtual PE. Read over the host link (charged): object, uncertain,
// tir, and per light nl, rv, through, shadowUncertain; and, only when the host needs them
// (some ray or shadow uncertain), the rays and the hit points. Left on the array (read
// uncharged for the emulation's next bounce): the children's origin and directions.
struct BounceOutputs {
  std::vector<int64_t> object;     // index + 1 (0: a miss)
  std::vector<uint8_t> uncertain;  // the first hit is not certain (host traces the ray)
  std::vector<uint8_t> tir;        // total internal reflection at the hit
  std::vector<uint8_t> inside;     // the ray met its object from inside
  std::vector<std::vector<int64_t>> nl, rv, through;  // [light][pe]
  std::vector<std::vector<uint8_t>> shadowUncertain;  // [light][pe]
  std::vector<int64_t> o[3], d[3];               // the rays as the array holds them (when read)
  std::vector<int64_t> p[3];                     // hit points (children's origin)
  std::vector<int64_t> mirror[3], refracted[3];  // the children's directions
  int64_t hostLinkBits = 0;                      // bits read over the host link
  struct {
    std::vector<int64_t> o[3], d[3];  // with `audit`: every ray as the array held it (uncharged)
  } audit;
};

// Runs the bounce on machine m (one virtual PE per ray of `in`), charging m's report.
// With `audit` (tests) out.audit gets every ray's origin and normalised direction, uncharged.
void RunBounce(bitserial::Machine& m, const SecondaryPlan& plan, bool intersect,
               const BounceInputs& in, BounceOutputs& out, bool audit = false);

// Whether the bounce's program fits `layers` layers of `profile`'s PE memory: run once on one
// virtual PE of those capacities (allocation is first fit in program order and reads no PE
// value, as the primary pass's MeasureProgram).
bool BounceFits(const bitserial::MachineProfile& profile, int layers, const SecondaryPlan& plan,
                bool intersect);

// The PE memory, in bits per virtual PE, that the bounce's light records alone hold until the
// host reads them: every light's N·L and R·V (s1.F, s3.F), its shadow product (u1.F) and its
// uncertainty flag — a lower bound of what the program needs, known without running it
// (BounceFits runs the program, 3 ms a light on this kind of host: a scene of 10^6 lights would
// run for most of an hour before it is found not to fit). Saturates at INT64_MAX.
int64_t LightRecordBits(const SecondaryPlan& plan);

}  // namespace zephyr::wavefront
