// Kernels on data that varies across the PE array: add, subtract,
// multiply (multi x multi, a 1-bit multiplier, a uni constant, square, float), host
// transfers and mesh shifts with operands whose bits differ from word to word and from PE
// to PE in every pattern a kernel could special-case — a single PE different (at a word's
// and a vector's edges, the last PE), a partial last word, uniform words next to mixed ones,
// one word different, alternating PEs, carries rippling in one PE only — on machines of one
// full layer, several layers with a partial last word, the MPP, and arrays whose planes are
// not a whole number of the add's strips (24 and 40 words a layer), on every compiled
// Highway target.
// Every PE's result bits and overflow flag equal the fixed:: (or plain C++) reference's.
// Also: LoadRaw of a list shorter than the PEs into planes that held other data leaves 0 in
// every PE past the list (bitserial/multi.h).
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <functional>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "bitserial/float.h"
#include "bitserial/multi.h"
#include "fixed/float.h"
#include "fixed/format.h"
#include "tests/bitserial/testing.h"

namespace zephyr::bitserial {
namespace {

using fixed::Fixed;
using fixed::Format;
using fixed::Policy;
using testutil::ForEachTarget;
using testutil::kPolicies;

// A machine: a profile's table with physicalPes replaced (0 keeps it), and its virtual PEs.
// The kernels load whole, aligned vectors (8 words on AVX-512), so a layer must be a multiple
// of 512 PEs: 1536 (24 words) and 2560 (40 words) are not a whole number of the add's
// 4-vector strips (32 words on AVX-512, 16 on AVX2), so its one-vector tail runs.
struct Geometry {
  const char* name;
  const char* profile;
  int physicalPes;
  int64_t pes;
};
const Geometry kGeometries[] = {
    {"wavetracer, one full layer (128 words)", "wavetracer", 0, 8192},
    {"wavetracer, two layers and 37 PEs (a partial last word)", "wavetracer", 0, 2 * 8192 + 37},
    {"mpp, 16384 PEs less 5 (a partial last word)", "mpp", 0, 16384 - 5},
    {"1536 PEs a layer (24 words), two layers less 13 PEs", "wavetracer", 1536, 2 * 1536 - 13},
    {"2560 PEs a layer (40 words), one full layer", "wavetracer", 2560, 2560},
};

MachineProfile ProfileOf(const Geometry& g) {
  const MachineProfile base = Profile(g.profile);
  if (g.physicalPes == 0) return base;
  // The base profile's costs on another geometry, read back as a file (so the reader checks it).
  MachineProfile p = base;
  p.name = "test";
  p.physicalPes = g.physicalPes;
  p.shapes = {MeshShape{{64, g.physicalPes / 64}}};
  return ProfileFromJson(p.FileText(), "test geometry");
}

// A pattern: one raw value per PE (two's complement, any int64; reduced to the format).
struct Pattern {
  std::string name;
  std::function<int64_t(int64_t pe, int64_t pes)> value;
};

// Raw values of `width` bits (signed: sign-extended) from 64 random bits.
int64_t Reduce(uint64_t bits, const Format& f) {
  const int w = f.Width();
  if (w >= 64) return static_cast<int64_t>(bits);
  bits &= (uint64_t{1} << w) - 1;
  if (f.isSigned && (bits >> (w - 1)) & 1) return static_cast<int64_t>(bits - (uint64_t{1} << w));
  return static_cast<int64_t>(bits);
}

uint64_t Hash(uint64_t x) {  // splitmix64
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// The patterns for one operand (seed: which operand). `base` and `other` are two fixed
// values of the format (uniform data and the odd one out; they differ in bit 0, and a 1-bit
// format's base is 1, so its uniform plane is all ones).
std::vector<Pattern> Patterns(const Format& f, uint64_t seed) {
  const int64_t base = Reduce(Hash(seed) | 1, f), other = Reduce(Hash(seed + 1) & ~uint64_t{1}, f);
  const int64_t ones = Reduce(~uint64_t{0}, f);
  const int64_t top = f.isSigned ? Reduce(uint64_t{1} << (f.Width() - 1), f) : ones;  // min / max
  std::vector<Pattern> r;
  r.push_back({"zero everywhere", [](int64_t, int64_t) { return int64_t{0}; }});
  r.push_back({"all ones everywhere", [=](int64_t, int64_t) { return ones; }});
  r.push_back({"the range's end everywhere", [=](int64_t, int64_t) { return top; }});
  r.push_back({"random in every PE",
               [=](int64_t pe, int64_t) { return Reduce(Hash(seed * 7919 + pe), f); }});
  // One PE different, at a word's first and last bit, a 512-PE vector's edges, the middle
  // and the last PE.
  for (int64_t at :
       {int64_t{0}, int64_t{63}, int64_t{64}, int64_t{511}, int64_t{512}, int64_t{-2}, int64_t{-1}})
    r.push_back({at == -1   ? "one PE different: the last"
                 : at == -2 ? "one PE different: the middle one"
                            : fmt::format("one PE different: PE {}", at),
                 [=](int64_t pe, int64_t pes) {
                   const int64_t k = at == -1 ? pes - 1 : at == -2 ? pes / 2 : at;
                   return pe == k ? other : base;
                 }});
  // Uniform words (alternately all `base` and all ones) next to mixed ones (random).
  r.push_back({"uniform words next to mixed ones", [=](int64_t pe, int64_t) {
                 const int64_t w = pe / 64;
                 return w % 3 == 0 ? base : w % 3 == 1 ? Reduce(Hash(seed * 31 + pe), f) : ones;
               }});
  // One word of random PEs in uniform data; the last word random.
  r.push_back({"one mixed word (word 5) in uniform data", [=](int64_t pe, int64_t) {
                 return pe / 64 == 5 ? Reduce(Hash(seed * 37 + pe), f) : base;
               }});
  r.push_back({"the last word mixed", [=](int64_t pe, int64_t pes) {
                 return pe / 64 == (pes - 1) / 64 ? Reduce(Hash(seed * 41 + pe), f) : base;
               }});
  r.push_back({"alternating PEs", [=](int64_t pe, int64_t) { return pe % 2 ? other : base; }});
  // One bit plane different in one PE (a carry or a partial product in one PE only).
  r.push_back({"one bit flipped in one PE", [=](int64_t pe, int64_t pes) {
                 return pe == pes / 3 ? Reduce(static_cast<uint64_t>(base) ^ 1, f) : base;
               }});
  return r;
}

// Runs `body` on one geometry per target: a fresh machine each time (a machine picks its
// kernels when it is built).
void EveryTarget(const Geometry& g, const std::function<void(Machine&)>& body) {
  const MachineProfile profile = ProfileOf(g);
  ForEachTarget([&] {
    Machine m(profile, g.pes);
    body(m);
  });
}

// One operation's reference per PE, cached by operand pair (patterns repeat values).
struct Expected {
  std::vector<int64_t> raw;
  std::vector<uint8_t> overflow;
};
using RefOp = std::function<Fixed(const Fixed&, const Fixed&, fixed::Status*)>;
Expected Reference(const std::vector<int64_t>& a, const Format& fa, const std::vector<int64_t>& b,
                   const Format& fb, const RefOp& op) {
  std::map<std::pair<int64_t, int64_t>, std::pair<int64_t, bool>> cache;
  Expected e;
  for (size_t i = 0; i < a.size(); ++i) {
    auto [it, fresh] = cache.try_emplace({a[i], b[i]});
    if (fresh) {
      fixed::Status st;
      const Fixed r = op(Fixed{fa, fixed::BigInt(a[i])}, Fixed{fb, fixed::BigInt(b[i])}, &st);
      it->second = {static_cast<int64_t>(r.raw), st.overflow};
    }
    e.raw.push_back(it->second.first);
    e.overflow.push_back(it->second.second);
  }
  return e;
}

std::vector<int64_t> Values(const Pattern& p, const Format& f, int64_t pes) {
  std::vector<int64_t> v(pes);
  for (int64_t pe = 0; pe < pes; ++pe) v[pe] = Reduce(static_cast<uint64_t>(p.value(pe, pes)), f);
  return v;
}

// Compares the engine's raw results and flags with the reference in every PE; reports the
// first few differences.
void ExpectSame(const Machine& m, const Multi& r, const Expected& want, const std::string& what) {
  const std::vector<int64_t> got = r.ReadRaw();
  int bad = 0;
  for (size_t pe = 0; pe < want.raw.size() && bad < 3; ++pe)
    if (got[pe] != want.raw[pe] || m.Overflow(static_cast<int64_t>(pe)) != bool(want.overflow[pe]))
      ++bad, ADD_FAILURE() << what << " [" << m.Kernels().target << "] PE " << pe << ": got "
                           << got[pe] << " ovf " << m.Overflow(static_cast<int64_t>(pe))
                           << ", want " << want.raw[pe] << " ovf " << int(want.overflow[pe]);
}

struct Binary {
  const char* name;
  Format fa, fb, out;
  Policy policy;
  std::function<Multi(const Multi&, const Multi&)> engine;
  RefOp ref;
};

// Add, subtract and multiply in formats that exercise each kernel path: exact (no bit
// dropped, the fused add), rounding and saturating (roundFit), overflow in the top bit, a
// 64-bit add, a product wider and narrower than its operands, a 1-bit multiplier (every
// row the same plane: all ones in every PE of a full layer is the uni-constant path).
std::vector<Binary> BinaryOps() {
  const Format s16 = Format::Signed(15, 0), s3_12 = Format::Signed(3, 12),
               u9 = Format::Unsigned(9, 0), s64 = Format::Signed(63, 0),
               s20_8 = Format::Signed(20, 8), u1 = Format::Unsigned(1, 0);
  const Policy floorWrap = kPolicies[0], nearSat = kPolicies[3], nearWrap = kPolicies[1];
  auto add = [](Format out, Policy p) {
    return [=](const Multi& a, const Multi& b) { return Add(a, b, out, p); };
  };
  auto sub = [](Format out, Policy p) {
    return [=](const Multi& a, const Multi& b) { return Sub(a, b, out, p); };
  };
  auto mul = [](Format out, Policy p) {
    return [=](const Multi& a, const Multi& b) { return Mul(a, b, out, p); };
  };
  using fixed::Status;
  auto refAdd = [](Format out, Policy p) {
    return [=](const Fixed& a, const Fixed& b, Status* s) { return fixed::Add(a, b, out, p, s); };
  };
  auto refSub = [](Format out, Policy p) {
    return [=](const Fixed& a, const Fixed& b, Status* s) { return fixed::Sub(a, b, out, p, s); };
  };
  auto refMul = [](Format out, Policy p) {
    return [=](const Fixed& a, const Fixed& b, Status* s) { return fixed::Mul(a, b, out, p, s); };
  };
  const Format s17 = Format::Signed(16, 0), s2_12 = Format::Signed(2, 12);
  const Format s31 = Format::Signed(31, 0), s4_10 = Format::Signed(4, 10);
  const Format s12_0 = Format::Signed(11, 0);
  return {
      {"add s15.0 + s15.0 -> s16.0 exact", s16, s16, s17, floorWrap, add(s17, floorWrap),
       refAdd(s17, floorWrap)},
      {"add s15.0 + s15.0 -> s15.0 wrap (overflow)", s16, s16, s16, floorWrap, add(s16, floorWrap),
       refAdd(s16, floorWrap)},
      {"add s3.12 + u9.0 -> s2.12 nearest saturate", s3_12, u9, s2_12, nearSat, add(s2_12, nearSat),
       refAdd(s2_12, nearSat)},
      {"add s63.0 + s63.0 -> s63.0 wrap", s64, s64, s64, floorWrap, add(s64, floorWrap),
       refAdd(s64, floorWrap)},
      {"sub s3.12 - s15.0 -> s4.10 nearest wrap", s3_12, s16, s4_10, nearWrap, sub(s4_10, nearWrap),
       refSub(s4_10, nearWrap)},
      {"sub u9.0 - u9.0 -> u9.0 saturate", u9, u9, u9, kPolicies[2], sub(u9, kPolicies[2]),
       refSub(u9, kPolicies[2])},
      {"mul s15.0 x s15.0 -> s31.0 exact", s16, s16, s31, floorWrap, mul(s31, floorWrap),
       refMul(s31, floorWrap)},
      {"mul s3.12 x s15.0 -> s20.8 nearest saturate", s3_12, s16, s20_8, nearSat,
       mul(s20_8, nearSat), refMul(s20_8, nearSat)},
      {"mul s15.0 x u9.0 -> s11.0 wrap (overflow)", s16, u9, s12_0, floorWrap,
       mul(s12_0, floorWrap), refMul(s12_0, floorWrap)},
      {"mul s63.0 x s63.0 -> s63.0 wrap", s64, s64, s64, floorWrap, mul(s64, floorWrap),
       refMul(s64, floorWrap)},
      {"mul s15.0 x u1.0 -> s15.0", s16, u1, s16, floorWrap, mul(s16, floorWrap),
       refMul(s16, floorWrap)},
  };
}

TEST(BitserialPatterns, AddSubMulEqualFixedForEveryPatternGeometryAndTarget) {
  int cases = 0;
  for (const Geometry& g : kGeometries)
    for (const Binary& op : BinaryOps()) {
      // Each pattern of a against random b, each of b against random a, and each non-random
      // pattern on both sides (the same PE different in both).
      const std::vector<Pattern> pa = Patterns(op.fa, 1), pb = Patterns(op.fb, 2);
      std::vector<std::pair<const Pattern*, const Pattern*>> pairs;
      for (size_t i = 0; i < pa.size(); ++i) pairs.push_back({&pa[i], &pb[3]});
      for (size_t i = 0; i < pb.size(); ++i) pairs.push_back({&pa[3], &pb[i]});
      for (size_t i = 4; i < pa.size(); ++i) pairs.push_back({&pa[i], &pb[i]});
      for (auto [x, y] : pairs) {
        const std::vector<int64_t> a = Values(*x, op.fa, g.pes), b = Values(*y, op.fb, g.pes);
        const Expected want = Reference(a, op.fa, b, op.fb, op.ref);
        const std::string what =
            fmt::format("{}; a: {}, b: {}; {}", op.name, x->name, y->name, g.name);
        EveryTarget(g, [&](Machine& m) {
          Multi ma(m, op.fa, "a"), mb(m, op.fb, "b");
          ma.LoadRaw(a), mb.LoadRaw(b);
          m.ClearFlags();
          ExpectSame(m, op.engine(ma, mb), want, what);
        });
        ++cases;
      }
    }
  EXPECT_EQ(cases, 5 * 11 * 44);
}

// A uni constant's rows (the all-ones plane repeated: the kernel's AND-free path) and
// squaring, against every pattern of the multiplicand.
TEST(BitserialPatterns, MulByUniAndSquareEqualFixedForEveryPatternGeometryAndTarget) {
  const Format s16 = Format::Signed(15, 0), s3_12 = Format::Signed(3, 12);
  const Format out = Format::Signed(18, 6);
  const Policy p = kPolicies[3];
  for (const Geometry& g : kGeometries)
    for (const Format& fa : {s16, s3_12})
      for (const Pattern& x : Patterns(fa, 5)) {
        const std::vector<int64_t> a = Values(x, fa, g.pes);
        for (const Fixed& c : {fixed::FromDouble(-2.75, Format::Signed(3, 2)),
                               Fixed{Format::Signed(7, 0), fixed::BigInt(0x55)},
                               Fixed{Format::Unsigned(8, 0), fixed::BigInt(0xFF)}}) {
          const Expected want =
              Reference(a, fa, a, fa, [&](const Fixed& v, const Fixed&, fixed::Status* s) {
                return fixed::Mul(v, c, out, p, s);
              });
          const std::string what =
              fmt::format("mul-uni {} x {}; {}; {}", fa.Name(), fixed::ToString(c), x.name, g.name);
          EveryTarget(g, [&](Machine& m) {
            Multi ma(m, fa, "a");
            ma.LoadRaw(a);
            m.ClearFlags();
            ExpectSame(m, Mul(ma, Uni{c}, out, p), want, what);
          });
        }
        const Expected sq =
            Reference(a, fa, a, fa, [&](const Fixed& v, const Fixed&, fixed::Status* s) {
              return fixed::Mul(v, v, out, p, s);
            });
        const std::string what = fmt::format("square {}; {}; {}", fa.Name(), x.name, g.name);
        EveryTarget(g, [&](Machine& m) {
          Multi ma(m, fa, "a");
          ma.LoadRaw(a);
          m.ClearFlags();
          ExpectSame(m, Square(ma, out, p), sq, what);
        });
      }
}

// The float multiply's product is the kernel's other output path (stored planes, not
// fitted); float add runs the add, select and logic kernels on every pattern.
TEST(BitserialPatterns, FloatMulAndAddEqualTheReferenceForEveryPatternGeometryAndTarget) {
  const fixed::FloatFormat f = fixed::FloatFormat::Binary32();
  const Format u32 = Format::Unsigned(32, 0);
  for (const Geometry& g : kGeometries) {
    const std::vector<Pattern> pa = Patterns(u32, 7), pb = Patterns(u32, 8);
    for (size_t i = 0; i < pa.size(); ++i) {
      // Each pattern of a against random b (zero b against random a).
      const std::vector<int64_t> a = Values(pa[i], u32, g.pes);
      const std::vector<int64_t> b = Values(pb[i == 3 ? 0 : 3], u32, g.pes);
      std::vector<uint64_t> ua(a.begin(), a.end()), ub(b.begin(), b.end());
      std::vector<uint64_t> mul(g.pes), add(g.pes);
      for (int64_t pe = 0; pe < g.pes; ++pe)
        mul[pe] = fixed::FloatMul(f, ua[pe], ub[pe]), add[pe] = fixed::FloatAdd(f, ua[pe], ub[pe]);
      EveryTarget(g, [&](Machine& m) {
        MultiFloat x(m, f, "a"), y(m, f, "b");
        x.Load(ua), y.Load(ub);
        const std::vector<uint64_t> gotMul = Mul(x, y).Read(), gotAdd = Add(x, y).Read();
        const std::string what = fmt::format("{}; {} [{}]", pa[i].name, g.name, m.Kernels().target);
        EXPECT_EQ(gotMul, mul) << "fmul " << what;
        EXPECT_EQ(gotAdd, add) << "fadd " << what;
      });
    }
  }
}

// Host transfers (LoadRaw/ReadRaw, the 64-PE transposes, and Load/Read) of every pattern
// and width, and mesh shifts (each layer its own mesh, 0 from outside) against a plain C++
// shift of the values.
TEST(BitserialPatterns, TransfersAndMeshShiftsForEveryPatternGeometryAndTarget) {
  for (const Geometry& g : kGeometries)
    for (const Format& f : {Format::Unsigned(1, 0), Format::Signed(15, 0), Format::Signed(40, 23),
                            Format::Unsigned(64, 0)})
      for (const Pattern& x : Patterns(f, 9)) {
        const std::vector<int64_t> v = Values(x, f, g.pes);
        const std::string what = fmt::format("{} {}; {}", f.Name(), x.name, g.name);
        EveryTarget(g, [&](Machine& m) {
          Multi a(m, f, "a");
          a.LoadRaw(v);
          ASSERT_EQ(a.ReadRaw(), v) << what;
          if (f.Width() < 64) {
            for (int64_t pe = 0; pe < g.pes; pe += 97)
              ASSERT_EQ(static_cast<int64_t>(a.At(pe).raw), v[pe]) << what;
          }
          if (f.Width() <= 16) {  // Load/Read through Fixed values (slow: narrow formats only)
            std::vector<Fixed> fv;
            for (int64_t r : v) fv.push_back(Fixed{f, fixed::BigInt(r)});
            Multi b(m, f, "b");
            b.Load(fv);
            ASSERT_EQ(b.ReadRaw(), v) << what;
          }
          const MeshShape& shape = m.Shape();
          const int64_t pesPerLayer = m.Profile().physicalPes;
          for (int axis = 0; axis < static_cast<int>(shape.extent.size()); ++axis)
            for (int d : {1, -3}) {
              int64_t stride = 1;
              for (int i = 0; i < axis; ++i) stride *= shape.extent[i];
              const int extent = shape.extent[axis];
              std::vector<int64_t> want(g.pes, 0);
              for (int64_t pe = 0; pe < g.pes; ++pe) {
                const int64_t layer = pe / pesPerLayer, local = pe % pesPerLayer;
                const int64_t coord = (local / stride) % extent - d;
                const int64_t src = layer * pesPerLayer + local - d * stride;
                if (coord >= 0 && coord < extent && src < g.pes) want[pe] = v[src];
              }
              EXPECT_EQ(MeshShift(a, axis, d).ReadRaw(), want)
                  << "mesh shift axis " << axis << " by " << d << ", " << what;
            }
        });
      }
}

// LoadRaw of fewer values than PEs into planes that held other data: every PE past the
// list holds 0 (bitserial/multi.h), for lists ending inside a word, at a word's end, inside
// the last layer and empty; and Load (Fixed values) and MultiFloat::Load (+0) likewise.
TEST(BitserialPatterns, LoadRawOfAShortListLeavesZeroPastIt) {
  for (const Geometry& g : kGeometries)
    for (const Format& f : {Format::Unsigned(1, 0), Format::Signed(15, 0), Format::Signed(70, 6)}) {
      const MachineProfile profile = ProfileOf(g);
      Machine m(profile, g.pes);
      Multi a(m, f, "a");
      std::vector<int64_t> full(g.pes);
      for (int64_t pe = 0; pe < g.pes; ++pe) full[pe] = Reduce(Hash(pe) | 1, f);  // no zero
      for (int64_t n : {int64_t{0}, int64_t{1}, int64_t{63}, int64_t{64}, int64_t{100},
                        g.pes / 2 + 1, g.pes - 1}) {
        a.LoadRaw(full);  // the planes hold other data
        const std::vector<int64_t> part(full.begin(), full.begin() + n);
        a.LoadRaw(part);
        const std::string what =
            fmt::format("{} values of {} into {}; {}", n, g.pes, f.Name(), g.name);
        for (int64_t pe = 0; pe < g.pes; ++pe)
          for (int i = 0; i < f.Width(); ++i) {
            const bool want = pe < n && (i < 64 ? (uint64_t(part[pe]) >> i) & 1 : part[pe] < 0);
            if (a.BitAt(i, pe) != want) {
              ADD_FAILURE() << what << ": PE " << pe << " bit " << i;
              pe = g.pes;
              break;
            }
          }
        // The same through Load.
        if (f.Width() <= 16) {
          std::vector<Fixed> fv;
          for (int64_t r : part) fv.push_back(Fixed{f, fixed::BigInt(r)});
          a.LoadRaw(full);
          a.Load(fv);
          for (int64_t pe = n; pe < g.pes; ++pe)
            if (a.At(pe).raw != 0) {
              ADD_FAILURE() << "Load: " << what << ": PE " << pe;
              break;
            }
        }
      }
      // A float multi: +0 past the list.
      MultiFloat x(m, fixed::FloatFormat::Binary32(), "x");
      std::vector<uint64_t> bits(g.pes, 0xBF800000u);  // -1.0
      x.Load(bits);
      x.Load(std::vector<uint64_t>(bits.begin(), bits.begin() + 70));
      for (int64_t pe = 0; pe < g.pes; ++pe)
        if (x.At(pe) != (pe < 70 ? 0xBF800000u : 0u)) {
          ADD_FAILURE() << "MultiFloat::Load of 70 values; " << g.name << ": PE " << pe;
          break;
        }
    }
}

}  // namespace
}  // namespace zephyr::bitserial
