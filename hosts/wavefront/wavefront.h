// hosts/wavefront/wavefront.h — every ray on the array (the fifth method, `--method array`;
// docs/wavefront.md): after the SIMD primary pass, bounce by bounce (a wavefront), the
// emulated array computes every hit point, normal, shadow ray (with the transparent-shadow
// product), reflected and refracted ray, and every secondary ray's first hit, in fixed point
// with multi origins; the host only shades the local term from the records the array returns
// and sums the ray tree. Between bounces each physical PE may pack its live rays into its
// lowest virtual-PE layers (--compact local), so the controller runs only the layers some PE
// still needs.
//
//   simd::PrimaryPass pass = simd::RunPrimaryPass(scene, simdOptions);
//   wavefront::WavefrontResult r = wavefront::RenderWavefront(*tracer, pass, options, pixels,
//                                                            hostWork);
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bitserial/report.h"
#include "fixed/named.h"
#include "hosts/simd/pass.h"
#include "hosts/trace/tracer.h"

namespace zephyr::wavefront {

// Between bounces (docs/wavefront.md, "Compaction"): keep every ray in its slot (a second
// child goes to a new layer block) and run every layer; pack each physical PE's live rays
// into its lowest layers (PE-local masked moves, charged) and run only as many layers as the
// fullest PE holds (found by a charged global max); or pack them and then even the PEs' counts
// over the mesh (dimension exchange: PE p with p xor 2^k for every bit k of the PE index, the
// fuller sending half the difference; mesh shifts and moves charged).
enum class Compaction { kNone, kLocal, kMesh };
inline constexpr NamedValues<Compaction, 3> kCompactionNames{
    {{{Compaction::kNone, "none"}, {Compaction::kLocal, "local"}, {Compaction::kMesh, "mesh"}}}};

// The fraction bits of the secondary rays' numbers when the primary plan's are fewer: the
// multi origins carry each bounce's rounding (docs/wavefront.md, "Formats").
inline constexpr int kMinSecondaryFracBits = 16;

// The widest fraction bits of the secondary rays (--array-frac-bits 8..40).
inline constexpr int kMaxSecondaryFracBits = 40;

// The smallest object of a scene, by the size the array's secondary rays must resolve: a
// sphere's radius, a polygon's diameter (its vertices' widest distance), a cone's larger radius
// or its length if shorter; under a transform, that size times the transform's smallest
// stretch (bounded below by 1 / (√3 ‖A⁻¹‖∞)). object -1: a scene with no object.
struct SmallestObject {
  int object = -1;
  double size = 0;  // scene units
};
SmallestObject SmallestObjectOf(const Scene& scene);

// The secondary rays' t error bound and their cut-off ε must stay within half the smallest
// object's size (SmallestObjectOf): a larger bound drops or misorders hits between
// small, close objects (issue 39: t error 4.49 and ε 1.36 rendered 30 % of a scene's pixels up
// to 80 levels off seq). Without --array-frac-bits the fraction bits are raised until the plan
// resolves it; with the flag, or past the widest F the scene's extent allows, the method
// refuses naming the flag (docs/wavefront.md, "Formats").
inline constexpr double kResolvedFraction = 1.0 / 2;

// One secondary ray as the array held it and what the array found (tests: the exact check
// of every bounce, docs/wavefront.md "Accuracy"). The origin and direction are the array's
// fixed-point values, exactly; the ray ignores roots at or below epsilon, never meets `from`
// again when it leaves it outward, and meets it at its far root when it enters it.
struct AuditRay {
  int bounce = 0;
  Vec3 origin, direction;  // direction as the array normalised it (not exactly unit)
  int from = -1;           // the object it leaves (-1: none)
  bool outward = true;
  int object = -1;         // the array's first object (-1: none)
  bool uncertain = false;  // flagged: the host traced it instead
  double epsilon = 0;
};

// The exact (128-bit, hosts/trace/exact.h) first object along an audited ray with the rules it
// states (-1: none): what the array's answer must be wherever it did not flag it uncertain.
int ExactFirstObject(const Scene& scene, const AuditRay& ray);

struct WavefrontOptions {
  Compaction compaction = Compaction::kMesh;
  // Fraction bits F of the secondary rays' coordinates, directions and t (-1: the primary
  // plan's, at least kMinSecondaryFracBits); 8..40.
  int fracBits = -1;
  // Tests only: called for every live ray of every bounce after the first (none in a render).
  std::function<void(const AuditRay&)> audit;
};

// Local compaction of one bounce's slots (`live`, layer-major: slot = layer · pes + PE):
// each PE's live rays packed into its lowest layers in layer order. `destination` is each
// live slot's new slot (-1 for the others); `layers` the layers the controller then runs (the
// fullest PE's count); `moves` the masked moves it issues: for each source layer, one per
// destination layer some PE moves that layer's ray to (docs/wavefront.md, "Compaction").
struct Packing {
  std::vector<int64_t> destination;
  int64_t layers = 0, moves = 0;
};
Packing PackLayers(const std::vector<uint8_t>& live, int pes);

// The mesh balance after PackLayers, from each PE's count of rays (in its lowest layers):
// for each bit k of the PE index (partner p xor 2^k, `pes` a power of two), each pair's fuller
// PE sends floor(difference / 2) of its top rays to the other's next free layers. `rounds[k]`
// is the transfers round k issues (the largest any pair needs: each a record shifted both
// ways over the mesh); `counts` the counts after; `layers` the fullest PE's count after;
// `moves` each PE's sent (PE, layer) → (PE, layer) in order.
struct MeshBalance {
  std::vector<int64_t> counts, rounds;
  int64_t layers = 0;
  struct Move {
    int from, to;
    int64_t fromLayer, toLayer;
  };
  std::vector<Move> moves;
};
MeshBalance BalanceOverMesh(std::vector<int64_t> counts);

// The mesh distance, in PE hops, from PE p to its partner p xor `bit` in the balance's round
// `bit` (a power of two below the PE count): PE p sits at (p mod X, (p div X) mod Y, ...) of
// the mesh `extent` (x fastest, as bitserial::MeshShape; empty: a line of all PEs), so the bit
// lies along the axis a whose extents before it multiply to P <= bit < P · extent[a], and the
// partner is bit / P hops away along that axis. With a power-of-two PE count every extent is a
// power of two, so a round's partners differ along one axis only. Across all rounds the hops
// sum to the sum over axes of (extent - 1).
int MeshPartnerDistance(int bit, const std::vector<int>& extent);

// One bounce of the wavefront (bounce 1: the primary rays' hits; bounce k: the rays of ray-tree
// level k): what ran on the array and what the host did.
struct BounceReport {
  int bounce = 0;
  int64_t rays = 0;              // live rays (slots holding a ray of this level)
  int64_t hits = 0;              // of them, rays that met an object (shaded)
  int64_t layers = 0;            // virtual-PE layers the controller ran
  int64_t slots = 0;             // layers × physical PEs
  int passes = 0;                // array passes (layers per pass limited by the PE memory)
  double utilisation = 0;        // rays ÷ slots
  int64_t uncertainRays = 0;     // first hits the array could not certify (host traced them)
  int64_t uncertainShadows = 0;  // shadow products it could not certify (host recomputed them)
  int64_t spawned = 0;           // rays this bounce's hits spawned for the next
  int64_t totalInternalReflections = 0;  // of the hits on glass, those the array found TIR
  int64_t hostLinkBytes = 0;             // records read back over the host link
  bitserial::CycleReport cycles;         // the bounce's array passes and its compaction, summed
  double compactionCycles = 0;           // of which the compaction (moves and the global max)
  double hostSeconds = 0;  // wall time of the bounce on this host (emulation + shading)
};

struct WavefrontResult {
  Compaction compaction = Compaction::kMesh;
  int fracBits = 0, intBits = 0;  // the coordinates' format s<intBits>.<fracBits>
  double tErrorBound = 0;         // |t − t_exact| of a certain secondary hit (scene units)
  double epsilon = 0;             // secondary and shadow rays ignore hits nearer than this
  std::vector<BounceReport> bounces;
  bitserial::CycleReport cycles;  // every bounce's (not the primary pass's)
  // Every ray traced on the array by kind (RayKind order), for the report.
  uint64_t arrayRays[kRayKinds] = {};
};

// Before the primary pass: the UserError RenderWavefront would throw for the PE memory (its
// first bounce's program, and with depth > 1 and a material that reflects or transmits the
// later bounces' program, not fitting one virtual-PE layer of `profile`) or the mesh
// compaction's PE count, from the primary plan alone (the programs' sizes depend on the
// formats, not on the hits), so the array method refuses before the pass's minutes. It
// assumes some primary ray hits something (a view of nothing is refused too).
void CheckBeforePrimaryPass(const Scene& scene, const simd::PrimaryPlan& primary,
                            const WavefrontOptions& options, int depth,
                            const bitserial::MachineProfile& profile);

// The host memory the bounces' ray layout may take at its peak, in bytes: the slots of the
// deepest bounce, and before it a bounce's slots with its children's twice as many. Without
// compaction (`kNone`) a surface that both reflects and transmits puts its second child a whole
// layer block on, so a scene with such a material may double the layers at every level
// (`pixels` ÷ `pes` rounded up, times 2^(depth−1), at worst: one second child in the block's
// last layer doubles it); with `kLocal`/`kMesh`, or no such material, the layout holds each
// level's live rays, at most one per pixel per path, and this bound is not used (0 returned).
// The array method refuses before the primary pass when it exceeds the memory the process may
// still allocate (issue 39: `--compact none` at depth ≥ 10 ran out of memory).
uint64_t UncompactedLayoutBytes(const Scene& scene, int depth, int64_t pixels, int pes,
                                Compaction compaction);

// The primary pass's hits shaded by the wavefront: fills `pixels` (linear RGB, row-major,
// resized to the image) and the host's counted work (`hostWork`: the local shading from
// records, and the subtrees and shadow products the array could not certify). UserError for a
// scene the method cannot run (an object that is not an untransformed sphere, naming its
// file:line; a program PE memory cannot hold; the mesh compaction on a PE count that is not a
// power of two).
WavefrontResult RenderWavefront(const Tracer& tracer, const simd::PrimaryPass& pass,
                                const WavefrontOptions& options, std::vector<Vec3>& pixels,
                                TraceStats& hostWork);

}  // namespace zephyr::wavefront
