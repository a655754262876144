// Bit-serial floating point (bitserial/float.h) against the exact reference (fixed/
// float.h), and the reference against the host's IEEE binary32: exhaustive for tiny
// formats, edge-biased random pairs for binary32, on every compiled Highway target.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <functional>
#include <random>

#include "bitserial/float.h"
#include "fixed/float.h"
#include "hosts/cmd/command.h"
#include "tests/bitserial/testing.h"

namespace zephyr::bitserial {
namespace {

using fixed::FloatFormat;
using testutil::ForEachTarget;

using EngineOp = std::function<MultiFloat(const MultiFloat&, const MultiFloat&)>;
using RefOp = std::function<uint64_t(const FloatFormat&, uint64_t, uint64_t)>;

struct NamedOp {
  const char* name;
  EngineOp engine;
  RefOp reference;
};

const std::vector<NamedOp>& BinaryOps() {
  static const std::vector<NamedOp> ops = {
      {"add", [](auto& a, auto& b) { return Add(a, b); }, fixed::FloatAdd},
      {"sub", [](auto& a, auto& b) { return Sub(a, b); }, fixed::FloatSub},
      {"mul", [](auto& a, auto& b) { return Mul(a, b); }, fixed::FloatMul},
  };
  return ops;
}

// Runs op on the pairs (one pair per virtual PE) and compares every PE with the reference;
// returns the number of mismatches (the first few are printed).
int64_t Mismatches(const FloatFormat& f, const NamedOp& op, const std::vector<uint64_t>& a,
                   const std::vector<uint64_t>& b) {
  Machine m(Profile("wavetracer"), static_cast<int64_t>(a.size()));
  MultiFloat x(m, f, "a"), y(m, f, "b");
  x.Load(a);
  y.Load(b);
  const MultiFloat r = op.engine(x, y);
  int64_t bad = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const uint64_t want = op.reference(f, a[i], b[i]), got = r.At(static_cast<int64_t>(i));
    if (got != want && ++bad <= 5)
      ADD_FAILURE() << f.Name() << " " << op.name << " " << std::hex << a[i] << ", " << b[i]
                    << ": got " << got << " want " << want << " (" << m.Kernels().target << ")";
  }
  return bad;
}

std::vector<FloatFormat> TinyFormats() {
  return {{2, 1, true}, {3, 2, true}, {3, 2, false}, {4, 3, true}, {4, 3, false}, {2, 5, true}};
}

TEST(BitserialFloat, ExhaustiveTinyFormatsEveryTarget) {
  ForEachTarget([&] {
    for (const FloatFormat& f : TinyFormats()) {
      std::vector<uint64_t> a, b;
      const uint64_t n = uint64_t{1} << f.Width();
      for (uint64_t i = 0; i < n; ++i)
        for (uint64_t j = 0; j < n; ++j) a.push_back(i), b.push_back(j);
      for (const NamedOp& op : BinaryOps()) EXPECT_EQ(Mismatches(f, op, a, b), 0) << f.Name() << " " << op.name;
    }
  });
}

// Edge-biased binary32 patterns: special exponents and fractions, near ties, operands of
// nearly equal magnitude (cancellation), and uniform random bits.
std::vector<uint64_t> EdgeBiased(std::mt19937_64& rng, size_t count, std::vector<uint64_t>* partner) {
  std::vector<uint64_t> a;
  auto pick = [&]() -> uint32_t {
    const uint32_t sign = (rng() & 1) << 31;
    static const uint32_t exps[] = {0, 1, 2, 24, 100, 126, 127, 128, 150, 200, 253, 254, 255};
    static const uint32_t fracs[] = {0, 1, 2, 0x400000, 0x7fffff, 0x7ffffe, 0x3fffff, 0x400001};
    const uint32_t e = rng() % 3 ? static_cast<uint32_t>(rng() % 256) : exps[rng() % 13];
    const uint32_t fr = rng() % 2 ? static_cast<uint32_t>(rng() & 0x7fffff) : fracs[rng() % 8];
    return sign | (e << 23) | fr;
  };
  for (size_t i = 0; i < count; ++i) {
    const uint32_t x = rng() % 4 ? pick() : static_cast<uint32_t>(rng());
    uint32_t y;
    switch (rng() % 5) {
      case 0: y = x ^ 0x80000000u ^ static_cast<uint32_t>(rng() % 4); break;  // cancellation
      case 1: y = (x & 0x80000000u) | ((x & 0x7fffffffu) + static_cast<uint32_t>(rng() % 64 << 23) - (32u << 23)); break;
      case 2: y = static_cast<uint32_t>(rng()); break;
      default: y = pick(); break;
    }
    a.push_back(x);
    partner->push_back(y);
  }
  return a;
}

uint64_t HostBits(float v) {
  if (std::isnan(v)) return FloatFormat::Binary32().CanonicalNaN();
  return std::bit_cast<uint32_t>(v);
}

TEST(BitserialFloat, ReferenceIsTheHostsBinary32) {
  const FloatFormat f = FloatFormat::Binary32();
  std::mt19937_64 rng(7);
  std::vector<uint64_t> b;
  const std::vector<uint64_t> a = EdgeBiased(rng, 100000, &b);
  int64_t bad = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const float x = std::bit_cast<float>(static_cast<uint32_t>(a[i]));
    const float y = std::bit_cast<float>(static_cast<uint32_t>(b[i]));
    const std::pair<uint64_t, uint64_t> checks[] = {
        {fixed::FloatAdd(f, a[i], b[i]), HostBits(x + y)},
        {fixed::FloatSub(f, a[i], b[i]), HostBits(x - y)},
        {fixed::FloatMul(f, a[i], b[i]), HostBits(x * y)},
    };
    for (auto [ref, host] : checks)
      if (ref != host && ++bad <= 5)
        ADD_FAILURE() << std::hex << a[i] << " " << b[i] << ": ref " << ref << " host " << host;
  }
  EXPECT_EQ(bad, 0);
}

TEST(BitserialFloat, Binary32EdgeBiasedPairs) {
  const FloatFormat f = FloatFormat::Binary32();
  std::mt19937_64 rng(11);
  std::vector<uint64_t> b;
  const std::vector<uint64_t> a = EdgeBiased(rng, 100000, &b);
  for (const NamedOp& op : BinaryOps()) EXPECT_EQ(Mismatches(f, op, a, b), 0) << op.name;
  // Every compiled target on a smaller sample.
  std::vector<uint64_t> b2(b.begin(), b.begin() + 8192);
  const std::vector<uint64_t> a2(a.begin(), a.begin() + 8192);
  ForEachTarget([&] {
    for (const NamedOp& op : BinaryOps()) EXPECT_EQ(Mismatches(f, op, a2, b2), 0) << op.name;
  });
}

TEST(BitserialFloat, CyclesDoNotDependOnTheData) {
  const FloatFormat f = FloatFormat::Binary32();
  for (const NamedOp& op : BinaryOps()) {
    double first = -1;
    for (uint64_t seed : {1, 2, 3}) {
      Machine m(Profile("wavetracer"));
      std::mt19937_64 rng(seed);
      std::vector<uint64_t> va(m.VirtualPes()), vb(m.VirtualPes());
      for (auto& v : va) v = rng() & f.Mask();
      for (auto& v : vb) v = seed == 3 ? 0 : rng() & f.Mask();
      MultiFloat x(m, f, "a"), y(m, f, "b");
      x.Load(va), y.Load(vb);
      m.Report().Clear();
      op.engine(x, y);
      const double c = m.Report().TotalCycles();
      if (first < 0) first = c;
      EXPECT_EQ(c, first) << op.name;
    }
  }
}

}  // namespace
}  // namespace zephyr::bitserial

namespace zephyr::bitserial {
namespace {

TEST(BitserialFloat, MppReproducesBatcher1980FloatRows) {
  // Batcher 1980: 32-bit floating-point add 430 MOPS and multiply 216 MOPS on 16,384 PEs
  // at 100 ns, i.e. 16384 / (430e6 × 100e-9) = 381 and 759 cycles per operation. The
  // format is binary32 as the profile's machine kept it (mpp: flush to zero, assumed).
  const MachineProfile mpp = Profile("mpp");
  const fixed::FloatFormat f{8, 23, mpp.floatSubnormals};
  EXPECT_FALSE(f.subnormals);
  const double add = FloatOpCycles(mpp, "fadd", f), mul = FloatOpCycles(mpp, "fmul", f);
  EXPECT_NEAR(add, 16384 / (430e6 * 100e-9), 0.1 * 381);
  EXPECT_NEAR(mul, 16384 / (216e6 * 100e-9), 0.1 * 759);
  // The IEEE gradual underflow costs more (the denormalising shift before rounding).
  EXPECT_GT(FloatOpCycles(mpp, "fadd", fixed::FloatFormat::Binary32()), add);
}

TEST(BitserialFloat, CyclesCommandPrintsTheMppFloatRows) {
  // The same rows through `zephyr cycles` (--bits 32: binary32 as the profile keeps it).
  for (auto [op, published] : {std::pair{"fadd", 381.0}, std::pair{"fmul", 759.0}}) {
    const char* args[] = {"zephyr", "cycles", "--profile", "mpp", "--op", op, "--bits", "32", "--json"};
    testing::internal::CaptureStdout();
    EXPECT_EQ(RunZephyr(9, args), 0);
    const nlohmann::json j = nlohmann::json::parse(testing::internal::GetCapturedStdout());
    EXPECT_EQ(j["format"], "e8m23ftz");
    EXPECT_NEAR(j["cycles"].get<double>(), published, 0.1 * published) << op;
  }
  const char* bad[] = {"zephyr", "cycles", "--op", "fadd", "--float", "e1m99"};
  testing::internal::CaptureStderr();
  EXPECT_NE(RunZephyr(6, bad), 0);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("'e1m99'"), std::string::npos);
}

}  // namespace
}  // namespace zephyr::bitserial
