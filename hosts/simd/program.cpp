// hosts/simd/program.cpp — the array program of the SIMD primary pass (hosts/simd/program.h).
#include "hosts/simd/program.h"

#include <algorithm>

#include "bitserial/multi.h"
#include "fixed/check.h"
#include "hosts/simd/direction.h"
#include "hosts/simd/object.h"
#include "hosts/simd/ops.h"

namespace zephyr::simd {

using bitserial::Machine;
using bitserial::Multi;
using bitserial::Space;
using fixed::Fixed;
using fixed::Format;

namespace {

// Where the matrix lives: external memory, leaving the internal for the arithmetic, on a
// machine that has one; internal on one that has none (the MPP's 1 Kbit per PE, a DRAM
// subarray's rows).
Space MatrixSpace(Machine& m) {
  return m.Memory().Capacity(Space::kExternal) > 0 ? Space::kExternal : Space::kInternal;
}

// The per-pixel matrix on the array, in this order (docs/simd.md, "The matrix layout").
struct ArrayMatrix {
  ArrayMatrix(Machine& m, const PrimaryPlan& plan)
      : object(m, plan.object, "matrix.object", MatrixSpace(m)),
        t(m, plan.t, "matrix.t", MatrixSpace(m)),
        d{{Multi(m, plan.direction, "matrix.dx", MatrixSpace(m)),
           Multi(m, plan.direction, "matrix.dy", MatrixSpace(m)),
           Multi(m, plan.direction, "matrix.dz", MatrixSpace(m))},
          {}},
        grazing(m, bitserial::BoolFormat(), "matrix.grazing", MatrixSpace(m)),
        nearTie(m, bitserial::BoolFormat(), "matrix.nearTie", MatrixSpace(m)) {
    // --number float: the directions in the pass's float format too (internal memory: the
    // programs read them; the matrix keeps the fixed ones for the host).
    if (plan.number == NumberSystem::kFloat)
      for (int k = 0; k < 3; ++k)
        d.floats[k] =
            bitserial::MultiFloat(m, plan.floatFormat, std::string("d.float.") + "xyz"[k]);
  }
  Multi object, t;
  Directions d;  // d.fixed: the matrix's
  Multi grazing, nearTie;
};

// The host computes each pixel's eye ray and loads the directions (one plane per bit) into
// the machine's PEs (a layer block's own, from m.FirstPe(), of the array pass starting at
// the plan's PE `first`): PE k takes pixel pixels[k], or pixel k when `pixels` is empty
// (row-major).
void LoadDirections(Machine& m, ArrayMatrix& a, const PrimaryRays& rays, const PrimaryPlan& plan,
                    const std::vector<int64_t>& pixels, int64_t first) {
  const bool floats = plan.number == NumberSystem::kFloat;
  std::vector<int64_t> raw[3];
  std::vector<uint64_t> bits[3];
  for (int k = 0; k < 3; ++k)
    raw[k].resize(m.VirtualPes()), bits[k].resize(floats ? m.VirtualPes() : 0);
  for (int64_t i = 0; i < m.VirtualPes(); ++i) {
    const int64_t pe = first + m.FirstPe() + i, pixel = pixels.empty() ? pe : pixels[pe];
    const Vec3 dir = rays.At(int(pixel % plan.width), int(pixel / plan.width)).direction;
    for (int k = 0; k < 3; ++k) raw[k][i] = QuantiseDirection(dir[k], plan.dirFracBits);
    if (floats)
      for (int k = 0; k < 3; ++k) bits[k][i] = FloatOfDouble(plan.floatFormat, dir[k]);
  }
  for (int k = 0; k < 3; ++k) a.d.fixed[k].LoadRaw(raw[k]);
  if (floats)
    for (int k = 0; k < 3; ++k) a.d.floats[k].Load(bits[k]);
}

// Near ties per pair (docs/simd.md, "Uncertain pixels"): the final best k and another hit j
// are tied when t_j − e_j <= t_k + e_k. Each PE keeps lowBest = t − e of its current best
// and otherLow, the least t − e of every other hit so far; a displaced best's low joins
// otherLow. bestUnsure: the current best was itself uncertain (its e does not hold);
// tGraze: the least tLow of an uncertain candidate. bestPlane (only when some plane holds
// several polygons): the plane class of the current best (ObjectPlan::planeClass, 0: none).
struct Trackers {
  Trackers(Machine& m, const Fixed& tMax, const PrimaryPlan& plan)
      : tGraze(Broadcast(m, tMax)),
        otherLow(Broadcast(m, tMax)),
        lowBest(Broadcast(m, tMax)),
        bestUnsure(Broadcast(m, Fixed{bitserial::BoolFormat(), 0})) {
    if (plan.planeClasses > 0) bestPlane = Broadcast(m, Fixed{PlaneFormat(plan), 0});
  }
  static Format PlaneFormat(const PrimaryPlan& plan) {
    return Format::Unsigned(std::max(1, CeilLog2(double(plan.planeClasses) + 1)), 0);
  }
  Multi tGraze, otherLow, lowBest, bestUnsure, bestPlane;
};

// One object's candidate folded into the best hit so far and the trackers.
void FoldCandidate(Machine& m, const ObjectPlan& object, const PrimaryPlan& plan, ArrayMatrix& a,
                   Trackers& k) {
  const Format T = plan.t;
  const Candidate c = object.program->Run(m, a.d, nullptr);
  // t − e_i with e_i rounded up (an always-uncertain object's every hit is flagged, so its
  // e is never relied on); saturating down only widens the test.
  const double e = object.bounds.alwaysUncertain ? 0.0 : object.bounds.tError + plan.pass.Ulp();
  Multi low;
  WithExpectedSaturation(m, [&] {
    low = Sub(c.t, c.lowMargin.Empty() ? Broadcast(m, Tight(e, plan.fracBits)) : c.lowMargin, T,
              kSaturate);
  });
  Where(c.uncertain, [&] { k.tGraze = Min(k.tGraze, c.tLow, T); });
  const Multi closer = c.hit && (c.t < a.t);
  // A polygon in the best's plane has the best's t bit for bit and ties with it exactly: the
  // lower index (the best) stays first, as in the exact reference, and it is no near tie.
  Multi other = c.hit && !closer;
  if (object.planeClass > 0)
    other = other && !Equal(k.bestPlane, bitserial::Uni{Fixed{k.bestPlane.Format(),
                                                              fixed::BigInt(object.planeClass)}});
  Where(other, [&] { k.otherLow = Min(k.otherLow, low, T); });
  Where(closer, [&] {
    if (!k.bestPlane.Empty())
      k.bestPlane = Broadcast(m, Fixed{k.bestPlane.Format(), fixed::BigInt(object.planeClass)});
    k.otherLow = Min(k.otherLow, k.lowBest, T);
    k.lowBest = low;
    k.bestUnsure = c.uncertain;
    a.t = c.t;
    a.object = Broadcast(m, Fixed{plan.object, fixed::BigInt(object.index + 1)});
  });
}

// A flagged candidate or another hit matters only if it may lie in front of the final best's
// true t <= tBest + e_best (= 2·tBest − lowBest; tMax marks "none"; the limit's exact format
// cannot overflow). An uncertain best is grazing itself.
void SetFlags(Machine& m, const Fixed& tMax, ArrayMatrix& a, const Trackers& k) {
  const Multi limit = a.t + (a.t - k.lowBest), none = Broadcast(m, tMax);
  a.grazing = k.bestUnsure || ((k.tGraze <= limit) && (k.tGraze < none));
  a.nearTie = (k.otherLow <= limit) && (k.otherLow < none);
}

void ReadMatrix(Machine& m, const ArrayMatrix& a, MatrixRaw& r, int64_t passFirst) {
  const int64_t first = passFirst + m.FirstPe();
  auto read = [first](const Multi& x, auto& to) {
    const std::vector<int64_t> raw = x.ReadRaw();
    std::copy(raw.begin(), raw.end(), to.begin() + first);
  };
  read(a.object, r.object), read(a.t, r.t);
  for (int k = 0; k < 3; ++k) read(a.d.fixed[k], r.d[k]);
  read(a.grazing, r.grazing), read(a.nearTie, r.nearTie);
  m.Charge("hostRead", bitserial::HostTransferCost(1));  // the overflow flags
  for (int64_t pe = 0; pe < m.VirtualPes(); ++pe)
    r.overflow[first + pe] = m.Overflow(pe) || m.DivideByZero(pe);
}

// The bits live and the most live at once since the last ResetPeak (both spaces).
int64_t LiveBits(Machine& m) {
  return m.Memory().Used(Space::kInternal) + m.Memory().Used(Space::kExternal);
}
int64_t PeakBits(Machine& m) {
  return m.Memory().PeakUsed(Space::kInternal) + m.Memory().PeakUsed(Space::kExternal);
}

// The program; with `memory`, what each part allocates (the peaks restart at each object).
void Run(Machine& m, const PrimaryPlan& plan, const PrimaryRays& rays,
         const std::vector<int64_t>& pixels, int64_t first, MatrixRaw* raw, ProgramMemory* memory) {
  ArrayMatrix matrix(m, plan);
  LoadDirections(m, matrix, rays, plan, pixels, first);
  const Fixed tMax{plan.t, plan.t.MaxRaw()};
  matrix.t = Broadcast(m, tMax);
  Trackers trackers(m, tMax, plan);
  if (memory) memory->baseBits = LiveBits(m), memory->peakBits = PeakBits(m);
  for (const ObjectPlan& object : plan.objects) {
    if (memory) m.Memory().ResetPeak();
    FoldCandidate(m, object, plan, matrix, trackers);
    if (memory) {
      memory->objectBits.push_back(PeakBits(m) - memory->baseBits);
      memory->peakBits = std::max(memory->peakBits, PeakBits(m));
    }
  }
  if (memory) m.Memory().ResetPeak();
  SetFlags(m, tMax, matrix, trackers);
  if (memory) memory->peakBits = std::max(memory->peakBits, PeakBits(m));
  if (raw) ReadMatrix(m, matrix, *raw, first);
}

}  // namespace

void RunProgram(Machine& m, const PrimaryPlan& plan, const PrimaryRays& rays,
                const std::vector<int64_t>& pixels, int64_t first, MatrixRaw* raw) {
  Run(m, plan, rays, pixels, first, raw, nullptr);
}

ProgramMemory MeasureProgram(const PrimaryPlan& plan, const Camera& camera,
                             const bitserial::MachineProfile& profile) {
  // The smallest array the kernels run (512 PEs: one vector of the widest target,
  // bitserial/profile.cpp) with the profile's PE memory: the allocation is the same, and each
  // operation costs the host 8 words per bit-plane instead of a whole layer's.
  bitserial::MachineProfile one = profile;
  one.physicalPes = 512;
  one.shapes = {bitserial::MeshShape{{64, 8}}};
  Machine m(one, 1);
  ProgramMemory memory;
  Run(m, plan, PrimaryRays(camera), {}, 0, nullptr, &memory);
  return memory;
}

}  // namespace zephyr::simd
