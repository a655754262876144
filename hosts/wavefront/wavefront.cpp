// hosts/wavefront/wavefront.cpp — the wavefront driver (hosts/wavefront/wavefront.h): the
// bounces, the array passes each runs, the host's shading from the records, the children's
// slots and the compaction between bounces (docs/wavefront.md).
#include "hosts/wavefront/wavefront.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>

#include "bitserial/cost.h"
#include "bitserial/machine.h"
#include "bitserial/multi.h"
#include "fixed/check.h"
#include "hosts/trace/exact.h"
#include "hosts/wavefront/program.h"

namespace zephyr::wavefront {

using bitserial::Machine;
using bitserial::MicroOpCounts;
using bitserial::Operand;
using bitserial::Space;
using fixed::Format;

namespace {

// One ray slot of a bounce's layout (virtual PE = layer · physical PEs + PE).
struct Slot {
  int32_t pixel = -1;  // -1: no ray
  double weight = 0;   // the product of Ks / T from the primary ray to this one
  RayKind kind = RayKind::kPrimary;
  int64_t o[3] = {}, d[3] = {};  // raw, in the plan's coord and direction formats
  int64_t object = 0, t = 0;     // bounce 1 only: the primary pass's hit (index + 1, raw t)
  int64_t from = 0;              // the object the ray leaves (index + 1; 0: the eye)
  bool outward = true;           // it leaves that object outward
  double originError = 0;        // the t error of the hit it starts at (HitError)
  // Which ray of its pixel's tree: one bit per bounce below the primary (0: the first child,
  // 1: the second). The host sums a pixel's rays of a bounce in this order, so the image does
  // not depend on which PE or layer held them.
  uint64_t path = 0;
};

// One ray's share of its pixel, summed bounce by bounce in (pixel, path) order.
struct Share {
  int32_t pixel;
  uint64_t path;
  Vec3 colour;
  bool operator<(const Share& o) const {
    return pixel != o.pixel ? pixel < o.pixel : path < o.path;
  }
};

int64_t RawOf(double x, int frac) { return int64_t(std::llround(std::ldexp(x, frac))); }
double ValueOf(int64_t raw, int frac) { return std::ldexp(double(raw), -frac); }
// PE i's vector of three raw components with `frac` fraction bits.
Vec3 VectorOf(const std::vector<int64_t> (&v)[3], size_t i, int frac) {
  return {ValueOf(v[0][i], frac), ValueOf(v[1][i], frac), ValueOf(v[2][i], frac)};
}

// The bits of one ray record (origin and direction): what a move between layers copies.
Operand CoordOperand(const SecondaryPlan& p) { return {p.coord, Space::kExternal, false}; }
Operand DirectionOperand(const SecondaryPlan& p) { return {p.direction, Space::kExternal, false}; }
MicroOpCounts RecordCopy(const SecondaryPlan& p) {
  MicroOpCounts c;
  for (int k = 0; k < 3; ++k) {
    c += bitserial::CopyCost(CoordOperand(p), CoordOperand(p));
    c += bitserial::CopyCost(DirectionOperand(p), DirectionOperand(p));
  }
  const Operand from{p.index, Space::kExternal, false},
      flag{bitserial::BoolFormat(), Space::kExternal, false};
  c += bitserial::CopyCost(from, from);
  c += bitserial::CopyCost(flag, flag);
  return c;
}

}  // namespace

int ExactFirstObject(const Scene& scene, const AuditRay& a) {
  int best = -1;
  exact::Real bestT = 0;
  for (int i = 0; i < int(scene.objects.size()); ++i) {
    // A sphere is convex; a plane is met once.
    if (i == a.from && (a.outward || scene.objects[i].Kind() == ShapeKind::kPolygon)) continue;
    const auto t = exact::ObjectHit(scene, i, a.origin, a.direction, a.epsilon);
    if (t && (best < 0 || *t < bestT)) best = i, bestT = *t;
  }
  return best;
}

Packing PackLayers(const std::vector<uint8_t>& live, int pes) {
  ZEPHYR_CHECK(pes > 0 && live.size() % size_t(pes) == 0);
  const int64_t layers = int64_t(live.size()) / pes;
  Packing r;
  r.destination.assign(live.size(), -1);
  std::vector<int64_t> next(pes, 0);
  for (int64_t l = 0; l < layers; ++l) {
    std::vector<int64_t> to;  // this layer's destinations other than itself
    for (int pe = 0; pe < pes; ++pe) {
      const size_t s = size_t(l) * pes + pe;
      if (!live[s]) continue;
      const int64_t d = next[pe]++;
      r.destination[s] = d * pes + pe;
      r.layers = std::max(r.layers, d + 1);
      if (d != l) to.push_back(d);
    }
    std::sort(to.begin(), to.end());
    r.moves += std::unique(to.begin(), to.end()) - to.begin();
  }
  return r;
}

MeshBalance BalanceOverMesh(std::vector<int64_t> counts) {
  const int pes = int(counts.size());
  ZEPHYR_CHECK(pes > 0 && (pes & (pes - 1)) == 0);
  MeshBalance b;
  for (int bit = 1; bit < pes; bit <<= 1) {
    int64_t round = 0;
    for (int p = 0; p < pes; ++p) {
      const int q = p ^ bit;
      if (q < p) continue;
      const int from = counts[p] > counts[q] ? p : q, to = from == p ? q : p;
      const int64_t m = (counts[from] - counts[to]) / 2;
      for (int64_t j = 0; j < m; ++j) b.moves.push_back({from, to, --counts[from], counts[to]++});
      round = std::max(round, m);
    }
    b.rounds.push_back(round);
  }
  b.counts = counts;
  for (int64_t c : counts) b.layers = std::max(b.layers, c);
  return b;
}

int MeshPartnerDistance(int bit, const std::vector<int>& extent) {
  int64_t before = 1;  // the PEs of the axes before this one (their extents' product)
  for (const int e : extent) {
    if (bit < before * e) return int(bit / before);
    before *= e;
  }
  return int(bit / before);  // no shape (a line), or a bit beyond the shape's PEs
}

namespace {

std::vector<Slot> Balance(std::vector<Slot> packed, int pes, const SecondaryPlan& p, Machine& cm);

// Lays `children` (the next bounce's rays, in the layout without compaction: `layers` layers
// of `pes` PEs) out for the next bounce, charging `cm` (one layer of the machine) for the
// moves. kNone keeps the layout; kLocal packs each PE's rays into its lowest layers
// (PackLayers): per source layer a counter increment, per move a compare of the counter with
// the destination (the mask) and the record's masked copy, and the global max of the
// counters that tells the controller how many layers to run.
std::vector<Slot> LayOut(std::vector<Slot> children, int64_t layers, int pes, Compaction policy,
                         const SecondaryPlan& p, Machine& cm) {
  if (policy == Compaction::kNone) {
    // Trailing layers no PE uses are not allocated (the controller knows which it wrote).
    int64_t last = 0;
    for (int64_t s = 0; s < int64_t(children.size()); ++s)
      if (children[s].pixel >= 0) last = s / pes + 1;
    children.resize(size_t(last) * pes);
    return children;
  }
  std::vector<uint8_t> live(children.size());
  for (size_t s = 0; s < children.size(); ++s) live[s] = children[s].pixel >= 0;
  const Packing packing = PackLayers(live, pes);
  std::vector<Slot> packed(size_t(packing.layers) * pes);
  for (size_t s = 0; s < children.size(); ++s)
    if (live[s]) packed[size_t(packing.destination[s])] = std::move(children[s]);
  const Format counter = Format::Unsigned(simd::IntBitsFor(double(layers)) + 1, 0);
  const Operand cnt{counter, Space::kInternal, false}, uni{counter, Space::kInternal, true};
  MicroOpCounts move = bitserial::CompareCost(cnt, uni, Space::kInternal);
  move += RecordCopy(p);
  for (int64_t l = 0; l < layers; ++l)
    cm.Charge("compactCount", bitserial::AddCost(cnt, uni, cnt, {}));
  for (int64_t k = 0; k < packing.moves; ++k) cm.Charge("compactMove", move);
  if (policy == Compaction::kMesh) packed = Balance(std::move(packed), pes, p, cm);
  cm.Charge("compactMax", bitserial::ReduceCost(bitserial::ReduceKind::kMax, cnt));
  return packed;
}

// --compact mesh: the packed layout evened over the mesh (BalanceOverMesh). Charged per round
// k: the counts exchanged with the partner (a shift each way by its mesh distance, a compare,
// a subtract and a halving); per transfer of the round: each sender's record copied from its
// top layer into a buffer (one masked copy per distinct source layer), the buffer shifted
// both ways over the partner's distance, and the receivers' masked copies into their layers
// (one per distinct destination layer). PE p sits at (p mod X, p div X) of the profile's
// shape (MeshPartnerDistance: bit k < log2 X is 2^k PEs along the first axis, a higher bit
// 2^k / X along the second, and so on for a 3-D shape).
std::vector<Slot> Balance(std::vector<Slot> packed, int pes, const SecondaryPlan& p, Machine& cm) {
  const int64_t layers = int64_t(packed.size()) / pes;
  std::vector<int64_t> counts(pes, 0);
  for (int64_t s = 0; s < int64_t(packed.size()); ++s)
    if (packed[s].pixel >= 0) counts[s % pes] = s / pes + 1;
  const MeshBalance b = BalanceOverMesh(counts);
  std::vector<std::vector<Slot>> perPe(pes);
  for (int pe = 0; pe < pes; ++pe)
    for (int64_t l = 0; l < counts[pe]; ++l) perPe[pe].push_back(packed[size_t(l) * pes + pe]);
  for (const MeshBalance::Move& m : b.moves) {
    perPe[m.to].push_back(std::move(perPe[m.from].back()));
    perPe[m.from].pop_back();
  }
  std::vector<Slot> out(size_t(b.layers) * pes);
  for (int pe = 0; pe < pes; ++pe)
    for (size_t l = 0; l < perPe[pe].size(); ++l) out[l * pes + pe] = std::move(perPe[pe][l]);
  // The charges.
  const std::vector<int>& extent = cm.Shape().extent;
  const Format counter = Format::Unsigned(simd::IntBitsFor(double(layers + b.layers)) + 1, 0);
  const Operand cnt{counter, Space::kInternal, false};
  const Operand fields[] = {CoordOperand(p),
                            DirectionOperand(p),
                            {p.index, Space::kExternal, false},
                            {bitserial::BoolFormat(), Space::kExternal, false}};
  const int copies[] = {3, 3, 1, 1};
  size_t next = 0;
  int round = 0;
  for (int bit = 1; bit < pes; bit <<= 1, ++round) {
    const int distance = MeshPartnerDistance(bit, extent);
    MicroOpCounts exchange = bitserial::MeshShiftCost(cnt, distance);
    exchange += exchange;
    exchange += bitserial::CompareCost(cnt, cnt, Space::kInternal);
    exchange += bitserial::SubCost(cnt, cnt, cnt, {});
    cm.Charge("balanceCounts", exchange);
    // This round's moves, step by step (the j-th transfer of every pair at once).
    std::map<int64_t, std::pair<std::vector<int64_t>, std::vector<int64_t>>> steps;
    std::map<std::pair<int, int>, int64_t> sent;
    for (; next < b.moves.size(); ++next) {
      const MeshBalance::Move& m = b.moves[next];
      if ((m.from ^ m.to) != bit) break;
      const int64_t j = sent[{std::min(m.from, m.to), std::max(m.from, m.to)}]++;
      steps[j].first.push_back(m.fromLayer), steps[j].second.push_back(m.toLayer);
    }
    for (auto& [j, layersOf] : steps) {
      for (auto* v : {&layersOf.first, &layersOf.second}) {
        std::sort(v->begin(), v->end());
        v->erase(std::unique(v->begin(), v->end()), v->end());
      }
      MicroOpCounts transfer;
      for (int f = 0; f < 4; ++f)
        for (int c = 0; c < copies[f]; ++c) {
          MicroOpCounts shift = bitserial::MeshShiftCost(fields[f], distance);
          transfer += shift;
          transfer += shift;  // both ways
          for (size_t k = 0; k < layersOf.first.size() + layersOf.second.size(); ++k)
            transfer += bitserial::CopyCost(fields[f], fields[f]);
        }
      cm.Charge("balanceMove", transfer);
    }
  }
  return out;
}

// The layers per array pass: the most (up to `layers`) whose program fits the PE memory.
int LayersPerPass(const bitserial::MachineProfile& profile, int64_t layers,
                  const SecondaryPlan& plan, bool intersect) {
  // The lights' records bound the program from below (LightRecordBits): a memory that cannot
  // hold them is not tried by running the program.
  const int64_t records = LightRecordBits(plan);
  const auto mayFit = [&](const bitserial::MachineProfile& p, int layers) {
    return records <= (int64_t(p.internalBitsPerPe) + p.externalBitsPerPe) / layers &&
           BounceFits(p, layers, plan, intersect);
  };
  int l = int(std::min<int64_t>(layers, 1 << 20));
  while (!mayFit(profile, l)) {
    if (l == 1) {
      // Say how much it would take: the PE memory scaled until one layer fits.
      std::string needs;
      for (int scale = 2; scale <= 64; scale *= 2) {
        bitserial::MachineProfile larger = profile;
        larger.internalBitsPerPe *= scale, larger.externalBitsPerPe *= scale;
        if (mayFit(larger, 1)) {
          needs = "; it fits " + std::to_string(larger.internalBitsPerPe) + " internal + " +
                  std::to_string(larger.externalBitsPerPe) + " external bits, " +
                  std::to_string(scale) + " times these: --set internalBitsPerPe=" +
                  std::to_string(larger.internalBitsPerPe) +
                  " --set externalBitsPerPe=" + std::to_string(larger.externalBitsPerPe);
          break;
        }
      }
      const size_t lights = plan.lights[0].size();
      if (needs.empty() && records > 64 * (int64_t(profile.internalBitsPerPe) +
                                           profile.externalBitsPerPe))
        needs = fmt::format(
            "; its {} lights alone keep {} bits on every PE until the host reads them (N.L, R.V, "
            "the shadow product and its flag, {} bits a light), more than 64 times these: give "
            "fewer lights, or --method simd, whose host shades any number of lights",
            lights, records, records / int64_t(lights));
      throw UserError("the wavefront's bounce program does not fit one virtual-PE layer of the " +
                      profile.name + " PE memory (" + std::to_string(profile.internalBitsPerPe) +
                      " internal + " + std::to_string(profile.externalBitsPerPe) +
                      " external bits" + needs + "; docs/wavefront.md, \"Several array passes\")");
    }
    l = (l + 1) / 2;
  }
  return l;
}

// The secondary rays' plan at fraction bits F resolving the scene's smallest object
// (ResolvedSize): the option's F, refused naming --array-frac-bits when it does not resolve;
// else the primary plan's F (at least kMinSecondaryFracBits), raised one bit at a time until it
// does, refused when no F that fits the scene's extent does.
SecondaryPlan PlanResolvingSecondary(const Scene& scene, const WavefrontOptions& options,
                                     const simd::PrimaryPlan& primary) {
  const SmallestObject smallest = SmallestObjectOf(scene);
  auto resolves = [&](const SecondaryPlan& p) {
    return smallest.object < 0 || std::max(p.tError, p.epsilon) <= kResolvedFraction * smallest.size;
  };
  auto describe = [&](const SecondaryPlan& p) {
    return fmt::format(
        "at {} fraction bits the array's secondary rays have t error <= {:.3g} and ignore hits "
        "within {:.3g}, more than 1/{:g} of the scene's smallest object ({}: size {:.3g}; "
        "docs/wavefront.md, \"Formats\")",
        p.fracBits, p.tError, p.epsilon, 1 / kResolvedFraction,
        scene.objects[size_t(smallest.object)].where.ToString(), smallest.size);
  };
  const int start = options.fracBits > 0 ? options.fracBits
                                         : std::max(primary.fracBits, kMinSecondaryFracBits);
  SecondaryPlan first = PlanSecondary(scene, start, primary.tErrorBound);
  if (resolves(first)) return first;
  // The least F that resolves it, if any fits the extent (PlanSecondary refuses past that).
  int needed = -1;
  SecondaryPlan found;
  for (int F = start + 1; F <= kMaxSecondaryFracBits && needed < 0; ++F) {
    try {
      found = PlanSecondary(scene, F, primary.tErrorBound);
    } catch (const UserError&) {
      break;
    }
    if (resolves(found)) needed = F;
  }
  if (needed < 0)
    throw UserError(describe(first) + "; no width up to " +
                    std::to_string(kMaxSecondaryFracBits) +
                    " fraction bits that fits the scene's extent resolves it: render it with the "
                    "seq, simd or hetero method (--method)" +
                    (options.fracBits > 0
                         ? " (--array-frac-bits " + std::to_string(options.fracBits) + ")"
                         : std::string()));
  if (options.fracBits > 0)
    throw UserError(describe(first) + " (--array-frac-bits " + std::to_string(options.fracBits) +
                    "); give --array-frac-bits " + std::to_string(needed) +
                    " or more, or leave the flag out");
  return found;
}

void CheckMeshCompaction(const bitserial::MachineProfile& profile, Compaction compaction) {
  const int pes = profile.physicalPes;
  if (compaction == Compaction::kMesh && (pes & (pes - 1)) != 0)
    throw UserError(
        "the mesh compaction pairs PE p with p xor 2^k: it needs a power-of-two "
        "number of PEs, and profile " +
        profile.name + " has " + std::to_string(pes) + " (the local compaction needs none)");
}

}  // namespace

void CheckBeforePrimaryPass(const Scene& scene, const simd::PrimaryPlan& primary,
                            const WavefrontOptions& options, int depth,
                            const bitserial::MachineProfile& profile) {
  const SecondaryPlan plan = PlanResolvingSecondary(scene, options, primary);
  CheckMeshCompaction(profile, options.compaction);
  if (scene.objects.empty()) return;  // no hit, no bounce
  LayersPerPass(profile, 1, plan, false);
  const bool secondary = std::any_of(scene.materials.begin(), scene.materials.end(),
                                     [](const Material& m) { return m.ks > 0 || m.t > 0; });
  if (depth > 1 && secondary) LayersPerPass(profile, 1, plan, true);
}

uint64_t UncompactedLayoutBytes(const Scene& scene, int depth, int64_t pixels, int pes,
                                Compaction compaction) {
  const bool doubles = std::any_of(scene.materials.begin(), scene.materials.end(),
                                   [](const Material& m) { return m.ks > 0 && m.t > 0; });
  if (compaction != Compaction::kNone || !doubles || depth < 2 || pixels <= 0 || pes <= 0)
    return 0;
  // The deepest bounce's slots (S), and the one before it with its children (3 × S / 2); each
  // live slot also leaves one Share for the pixel sums. Saturates past 2^63.
  const double layers = std::ceil(double(pixels) / pes) * std::ldexp(1.0, depth - 1);
  const double bytes = layers * pes * (1.5 * sizeof(Slot) + sizeof(Share));
  return bytes >= 0x1p63 ? uint64_t(1) << 63 : uint64_t(bytes);
}

SmallestObject SmallestObjectOf(const Scene& scene) {
  SmallestObject smallest;
  for (size_t j = 0; j < scene.objects.size(); ++j) {
    const Primitive& o = scene.objects[j];
    double size = 0;
    if (const auto* s = std::get_if<Sphere>(&o.shape)) {
      size = s->radius;
    } else if (const auto* c = std::get_if<Cone>(&o.shape)) {
      size = std::min(std::max(c->baseRadius, c->apexRadius), Length(c->apex - c->base));
    } else {
      const auto& v = std::get<Polygon>(o.shape).vertices;
      for (size_t a = 0; a < v.size(); ++a)
        for (size_t b = a + 1; b < v.size(); ++b) size = std::max(size, Length(v[a] - v[b]));
    }
    if (o.transform) size /= std::sqrt(3.0) * o.transform->Inverse().LinearNormInf();
    if (smallest.object < 0 || size < smallest.size) smallest = {int(j), size};
  }
  return smallest;
}

namespace {

// One render's bounces as named stages, after pbrt-v4's wavefront integrator
// (docs/wavefront.md, "The bounces"): the primary pass's hits laid out as bounce 1's rays;
// then per bounce, batch by batch of layers, the array's pass (RunBounce) and the host's
// shading of each ray from its record, which spawns the next bounce's rays; the shares
// summed into the pixels in (pixel, path) order; the next layout. The compaction before a
// bounce (and the second children's copies) is charged to it, through `pending_`.
class Bounces {
 public:
  Bounces(const Tracer& tracer, const simd::PrimaryPass& pass, const WavefrontOptions& options,
          std::vector<Vec3>& pixels, TraceStats& hostWork)
      : tracer_(tracer),
        scene_(tracer.GetScene()),
        options_(options),
        profile_(pass.array.cycles.Profile()),
        pes_(profile_.physicalPes),
        depth_(tracer.Options().depth),
        lights_(scene_.lights.size()),
        plan_(PlanForPass(scene_, options, pass)),
        F_(plan_.fracBits),
        pixels_(pixels),
        hostWork_(hostWork) {
    CheckMeshCompaction(profile_, options.compaction);
    result_.compaction = options.compaction;
    result_.fracBits = F_, result_.intBits = plan_.intBits;
    result_.tErrorBound = plan_.tError, result_.epsilon = plan_.epsilon;
  }

  WavefrontResult Run(const simd::PrimaryMatrix& matrix) {
    const int64_t primaryLayers = PrimarySlots(matrix);
    pending_ = std::make_unique<Machine>(profile_, pes_);
    slots_ = LayOut(std::move(slots_), primaryLayers, pes_, options_.compaction, plan_, *pending_);
    for (int bounce = 1; bounce <= depth_ && !slots_.empty(); ++bounce) Bounce(bounce);
    return std::move(result_);
  }

 private:
  // The secondary rays' plan, with each object's primary t error (the pass's bound, or the
  // refine step's) for the hits bounce 1 starts from.
  static SecondaryPlan PlanForPass(const Scene& scene, const WavefrontOptions& options,
                                   const simd::PrimaryPass& pass) {
    SecondaryPlan plan = PlanResolvingSecondary(scene, options, pass.plan);
    plan.primaryErrors.assign(scene.objects.size(), pass.plan.tErrorBound);
    for (const simd::ObjectPlan& o : pass.plan.objects) {
      const double e = std::isfinite(o.bounds.tError) ? o.bounds.tError : 0;
      plan.primaryErrors.at(size_t(o.index)) =
          std::max(e, pass.refine ? pass.refine->tErrorBound : 0);
    }
    return plan;
  }

  // Bounce 1: the primary pass's hits, in its layout (pixel k in virtual PE k); a pixel whose
  // primary ray hit nothing is the background at once. The layers it fills.
  int64_t PrimarySlots(const simd::PrimaryMatrix& matrix) {
    const int64_t pixelCount = int64_t(matrix.hits.size());
    pixels_.assign(size_t(pixelCount), Vec3{});
    hostWork_.pixels += uint64_t(pixelCount);
    const int64_t layers = (pixelCount + pes_ - 1) / pes_;
    slots_.assign(size_t(layers) * pes_, Slot{});
    for (int64_t i = 0; i < pixelCount; ++i) {
      const PrimaryHit& h = matrix.hits[i];
      if (h.object < 0) {
        pixels_[i] = scene_.background;
        continue;
      }
      Slot& s = slots_[i];
      s.pixel = int32_t(i), s.weight = 1, s.kind = RayKind::kPrimary;
      for (int k = 0; k < 3; ++k)
        s.o[k] = RawOf(scene_.camera.from[k], F_), s.d[k] = RawOf(h.direction[k], F_);
      s.object = h.object + 1, s.t = RawOf(h.t, F_);
    }
    return layers;
  }

  void Bounce(int bounce) {
    const auto start = std::chrono::steady_clock::now();
    BounceReport& report = StartBounce(bounce);
    const bool intersect = bounce > 1;
    const int64_t layers = report.layers;
    const int perPass = LayersPerPassOf(layers, intersect);
    // The next bounce's rays, laid out without compaction: a first child in its parent's
    // slot, a second (the refracted ray of a surface that also reflects) `layers` layers on.
    children_.assign(bounce < depth_ ? slots_.size() * 2 : 0, Slot{});
    shares_.clear();
    anySecond_ = false;
    for (int64_t first = 0; first < layers; first += perPass) {
      const int64_t count = std::min<int64_t>(perPass, layers - first);
      RunBatch(report, bounce, size_t(first) * pes_, size_t(count) * pes_);
    }
    AddShares();
    NextLayout(bounce, layers);
    report.hostSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  // The bounce's report, charged with the compaction that made its layout.
  BounceReport& StartBounce(int bounce) {
    BounceReport& report = result_.bounces.emplace_back();
    report.bounce = bounce;
    report.cycles.Add(pending_->Report());
    result_.cycles.Add(pending_->Report());
    report.compactionCycles = pending_->Report().TotalCycles();
    pending_ = std::make_unique<Machine>(profile_, pes_);
    report.layers = int64_t(slots_.size()) / pes_, report.slots = report.layers * pes_;
    for (const Slot& s : slots_) report.rays += s.pixel >= 0;
    report.utilisation = report.slots ? double(report.rays) / double(report.slots) : 0;
    return report;
  }

  // The layers one pass of the bounce program takes (fitted once per layout and kind).
  int LayersPerPassOf(int64_t layers, bool intersect) {
    const auto key = std::make_pair(int(layers), intersect);
    if (!fitted_.count(key)) fitted_[key] = LayersPerPass(profile_, layers, plan_, intersect);
    return fitted_[key];
  }

  // One pass over slots [begin, begin + n): the array's records, then the host's shading of
  // each live ray from them.
  void RunBatch(BounceReport& report, int bounce, size_t begin, size_t n) {
    BounceInputs in;
    for (int k = 0; k < 3; ++k) in.o[k].resize(n), in.d[k].resize(n);
    in.object.resize(n), in.t.resize(n), in.from.resize(n);
    in.live.resize(n), in.outward.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const Slot& s = slots_[begin + i];
      for (int k = 0; k < 3; ++k) in.o[k][i] = s.o[k], in.d[k][i] = s.d[k];
      in.object[i] = s.object, in.t[i] = s.t, in.live[i] = s.pixel >= 0;
      in.from[i] = s.from, in.outward[i] = s.outward;
    }
    Machine m(profile_, int64_t(n));
    BounceOutputs out;
    RunBounce(m, plan_, bounce > 1, in, out, bool(options_.audit));
    report.cycles.Add(m.Report());
    result_.cycles.Add(m.Report());
    report.hostLinkBytes += out.hostLinkBits / 8;
    ++report.passes;
    for (size_t i = 0; i < n; ++i)
      if (slots_[begin + i].pixel >= 0) ShadeRay(report, bounce, out, i, begin + i);
  }

  // The host's part for the live ray in slot `slot` (PE i of the pass): its share of the
  // pixel from the array's record (or its whole subtree on the host where the array could
  // not certify its hit), and its children.
  void ShadeRay(BounceReport& report, int bounce, const BounceOutputs& out, size_t i, size_t slot) {
    const Slot& s = slots_[slot];
    const bool intersect = bounce > 1;
    if (intersect) ++result_.arrayRays[int(s.kind)];
    if (intersect && options_.audit) Audit(bounce, s, out, i);
    if (intersect && out.uncertain[i]) {
      // The array could not certify this ray's first hit: its whole subtree on the host,
      // from the ray as the array holds it.
      ++report.uncertainRays;
      const Vec3 o = VectorOf(out.o, i, F_), d = Normalize(VectorOf(out.d, i, F_));
      shares_.push_back(
          {s.pixel, s.path,
           tracer_.TraceRay(o, d, HostOffset(plan_, s.originError), bounce, s.kind, hostWork_) *
               s.weight});
      return;
    }
    const int64_t object = out.object[i] - 1;
    if (object < 0) {
      shares_.push_back({s.pixel, s.path, scene_.background * s.weight});
      return;
    }
    ++report.hits;
    // This hit's t error, for the host's offset from p and for its children's.
    const double hitError =
        HitError(plan_, bounce, int(object),
                 Normalize(Vec3{ValueOf(s.d[0], F_), ValueOf(s.d[1], F_), ValueOf(s.d[2], F_)}));
    ShadeHit(report, s, out, i, int(object), hitError);
    if (bounce < depth_) Spawn(report, s, out, i, slot, object, hitError);
  }

  void Audit(int bounce, const Slot& s, const BounceOutputs& out, size_t i) const {
    AuditRay a;
    a.bounce = bounce, a.from = int(s.from) - 1, a.outward = s.outward;
    a.object = int(out.object[i]) - 1, a.uncertain = out.uncertain[i];
    a.epsilon = plan_.epsilon;
    a.origin = VectorOf(out.audit.o, i, F_), a.direction = VectorOf(out.audit.d, i, F_);
    options_.audit(a);
  }

  // The local term at a certified hit from the record's per-light products; a shadow the
  // array could not certify is traced on the host from the hit point.
  void ShadeHit(BounceReport& report, const Slot& s, const BounceOutputs& out, size_t i,
                int object, double hitError) {
    result_.arrayRays[int(RayKind::kShadow)] += lights_;
    std::vector<double> nl(lights_), rv(lights_), through(lights_);
    const Vec3 p = VectorOf(out.p, i, F_);
    for (size_t j = 0; j < lights_; ++j) {
      nl[j] = ValueOf(out.nl[j][i], F_), rv[j] = ValueOf(out.rv[j][i], F_);
      through[j] = ValueOf(out.through[j][i], F_);
      if (out.shadowUncertain[j][i] && nl[j] > 0) {
        ++report.uncertainShadows;
        through[j] = tracer_.LightThrough(p, int(j), HostOffset(plan_, hitError), hostWork_);
      }
    }
    shares_.push_back(
        {s.pixel, s.path,
         tracer_.LocalFromRecord(object, nl.data(), rv.data(), through.data(), hostWork_) *
             s.weight});
  }

  // The hit's children: a reflected ray in the parent's slot, a transmitted (or totally
  // internally reflected) one there too or, when both spawn, `slots_.size()` slots on.
  void Spawn(BounceReport& report, const Slot& s, const BounceOutputs& out, size_t i, size_t slot,
             int64_t object, double hitError) {
    const Material& mat = scene_.materials[scene_.objects[object].material];
    Slot child;
    child.pixel = s.pixel;
    child.from = object + 1;
    child.originError = hitError;
    child.path = s.path << 1;
    for (int k = 0; k < 3; ++k) child.o[k] = out.p[k][i];
    size_t to = slot;
    if (mat.ks > 0) {
      child.weight = s.weight * mat.ks, child.kind = RayKind::kReflected;
      child.outward = !out.inside[i];
      for (int k = 0; k < 3; ++k) child.d[k] = out.mirror[k][i];
      children_[to] = child;
      to += slots_.size();
      child.path |= 1;
      ++report.spawned;
    }
    if (mat.t > 0) {
      const bool tir = out.tir[i];
      report.totalInternalReflections += tir;
      child.weight = s.weight * mat.t;
      child.kind = tir ? RayKind::kReflected : RayKind::kRefracted;
      child.outward = tir ? !out.inside[i] : bool(out.inside[i]);
      for (int k = 0; k < 3; ++k) child.d[k] = tir ? out.mirror[k][i] : out.refracted[k][i];
      children_[to] = child;
      anySecond_ |= to >= slots_.size();
      ++report.spawned;
    }
  }

  // The bounce's shares into their pixels, in (pixel, path) order.
  void AddShares() {
    std::sort(shares_.begin(), shares_.end());
    for (const Share& share : shares_) pixels_[share.pixel] += share.colour;
  }

  // The second children's masked copies into their layers (one per source layer), then the
  // next bounce's layout; both charged to the next bounce.
  void NextLayout(int bounce, int64_t layers) {
    if (!anySecond_ && bounce < depth_) children_.resize(slots_.size());
    for (int64_t l = 0; anySecond_ && l < layers; ++l)
      pending_->Charge("childCopy", RecordCopy(plan_));
    const int64_t childLayers = int64_t(children_.size()) / pes_;
    slots_ = bounce < depth_ ? LayOut(std::move(children_), childLayers, pes_,
                                      options_.compaction, plan_, *pending_)
                             : std::vector<Slot>{};
  }

  const Tracer& tracer_;
  const Scene& scene_;
  const WavefrontOptions& options_;
  const bitserial::MachineProfile& profile_;
  const int pes_, depth_;
  const size_t lights_;
  const SecondaryPlan plan_;
  const int F_;
  std::vector<Vec3>& pixels_;
  TraceStats& hostWork_;
  WavefrontResult result_;
  std::vector<Slot> slots_, children_;  // this bounce's rays; the next bounce's, uncompacted
  std::vector<Share> shares_;           // this bounce's shares of their pixels
  bool anySecond_ = false;              // some hit of this bounce spawned a second child
  std::unique_ptr<Machine> pending_;    // the work charged to the next bounce
  std::map<std::pair<int, bool>, int> fitted_;  // LayersPerPass by (layers, intersect)
};

}  // namespace

WavefrontResult RenderWavefront(const Tracer& tracer, const simd::PrimaryPass& pass,
                                const WavefrontOptions& options, std::vector<Vec3>& pixels,
                                TraceStats& hostWork) {
  return Bounces(tracer, pass, options, pixels, hostWork).Run(pass.matrix);
}

}  // namespace zephyr::wavefront
