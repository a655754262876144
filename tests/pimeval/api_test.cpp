// PIMeval's host API on the engine (tools/pimeval/, docs/pim.md): every call on every supported
// type against plain C++ computing PIMeval's semantics (the element widened to int64_t or
// uint64_t, the C++ operation, the result wrapped to the type; for PIM_FP32 the C++ float
// expression), edge values (INT64 min, UINT64 max, -0.0, NaN, infinities, subnormals, FLT_MAX),
// ranges at the object's ends and empty ones, errors for what is refused, the modelled time's
// parallelism (and the horizontal layout's passes).
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <type_traits>
#include <unistd.h>
#include <vector>

#include "tools/pimeval/libpimeval.h"

namespace {

template <typename T> constexpr PimDataType kType = PIM_INT8;
template <> constexpr PimDataType kType<int8_t> = PIM_INT8;
template <> constexpr PimDataType kType<int16_t> = PIM_INT16;
template <> constexpr PimDataType kType<int32_t> = PIM_INT32;
template <> constexpr PimDataType kType<int64_t> = PIM_INT64;
template <> constexpr PimDataType kType<uint8_t> = PIM_UINT8;
template <> constexpr PimDataType kType<uint16_t> = PIM_UINT16;
template <> constexpr PimDataType kType<uint32_t> = PIM_UINT32;
template <> constexpr PimDataType kType<uint64_t> = PIM_UINT64;

// PIMeval's widening: int64_t for signed types, uint64_t for unsigned.
template <typename T> using Wide = std::conditional_t<std::is_signed_v<T>, int64_t, uint64_t>;
template <typename T> T Wrap(uint64_t bits) { return static_cast<T>(bits); }
template <typename T> uint64_t U(T v) { return static_cast<uint64_t>(static_cast<Wide<T>>(v)); }

// Edge values first (min, max, 0, 1, -1 / all ones, min+1, max-1), then random bits.
template <typename T> std::vector<T> Values(size_t n, uint32_t seed) {
  const T lo = std::numeric_limits<T>::min(), hi = std::numeric_limits<T>::max();
  std::vector<T> v = {lo, hi, T(0), T(1), T(-1), T(lo + 1), T(hi - 1), T(2), T(hi / 2)};
  std::mt19937_64 rng(seed);
  while (v.size() < n) v.push_back(Wrap<T>(rng()));
  v.resize(n);
  if (seed % 2) std::rotate(v.begin(), v.begin() + 3, v.end());  // other edge pairs
  return v;
}

class Pim : public ::testing::Test {
 protected:
  // 1 rank x 2 banks x 2 subarrays x 512 columns = 2048 PEs, 1024 rows.
  void SetUp() override {
    ::unsetenv("ZEPHYR_MACHINE");
    ASSERT_EQ(pimCreateDevice(PIM_FUNCTIONAL, 1, 2, 2, 1024, 512), PIM_OK);
  }
  void TearDown() override { pimDeleteDevice(); }
};

template <typename T> std::vector<T> Read(PimObjId o, size_t n) {
  std::vector<T> v(n);
  EXPECT_EQ(pimCopyDeviceToHost(o, v.data()), PIM_OK);
  return v;
}

uint32_t FBits(float f) { return std::bit_cast<uint32_t>(f); }
float FOf(uint32_t b) { return std::bit_cast<float>(b); }
// A value as compared exactly: a float's pattern (NaN payloads, the sign of zero), else itself.
template <typename T> auto Exactly(T v) {
  if constexpr (std::is_floating_point_v<T>) return FBits(v); else return v;
}

// Objects a, b, d of type t and a BOOL c, all associated; a and b hold the host's n elements.
struct Operands {
  PimObjId a = -1, b = -1, d = -1, c = -1;
};
void AllocOperands(size_t n, PimDataType t, const void* a, const void* b, Operands* o) {
  o->a = pimAlloc(PIM_ALLOC_AUTO, n, t);
  ASSERT_GE(o->a, 0);
  o->b = pimAllocAssociated(o->a, t);
  o->d = pimAllocAssociated(o->a, t);
  o->c = pimAllocAssociated(o->a, PIM_BOOL);
  ASSERT_GE(o->b, 0);
  ASSERT_GE(o->d, 0);
  ASSERT_GE(o->c, 0);
  ASSERT_EQ(pimCopyHostToDevice(const_cast<void*>(a), o->a), PIM_OK);
  ASSERT_EQ(pimCopyHostToDevice(const_cast<void*>(b), o->b), PIM_OK);
}

// The conditionals on o's objects (a and b holding `a` and `b`) under a fixed pattern of c;
// `bits` is the scalar given to pimCondBroadcast and pimCondSelectScalar, `value` what it is.
template <typename T>
void CheckConditionals(const Operands& o, const std::vector<T>& a, const std::vector<T>& b,
                       uint64_t bits, T value) {
  const size_t n = a.size();
  std::vector<uint8_t> cond(n);
  for (size_t i = 0; i < n; ++i) cond[i] = (i * 7 + 3) % 5 < 2;
  ASSERT_EQ(pimCopyHostToDevice(cond.data(), o.c), PIM_OK);
  ASSERT_EQ(pimCopyObjectToObject(o.b, o.d), PIM_OK);
  ASSERT_EQ(pimCondCopy(o.c, o.a, o.d), PIM_OK);
  std::vector<T> got = Read<T>(o.d, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(Exactly(got[i]), Exactly(cond[i] ? a[i] : b[i])) << i;
  ASSERT_EQ(pimCondBroadcast(o.c, bits, o.d), PIM_OK);
  got = Read<T>(o.d, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(Exactly(got[i]), Exactly(cond[i] ? value : b[i])) << i;
  ASSERT_EQ(pimCondSelect(o.c, o.b, o.a, o.d), PIM_OK);
  got = Read<T>(o.d, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(Exactly(got[i]), Exactly(cond[i] ? b[i] : a[i])) << i;
  ASSERT_EQ(pimCondSelectScalar(o.c, o.a, bits, o.d), PIM_OK);
  got = Read<T>(o.d, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(Exactly(got[i]), Exactly(cond[i] ? a[i] : value)) << i;
}

template <typename T> void CheckEveryOperation(size_t n) {
  SCOPED_TRACE(testing::Message() << "type of " << sizeof(T) << " bytes, "
                                  << (std::is_signed_v<T> ? "signed" : "unsigned") << ", " << n
                                  << " elements");
  using W = Wide<T>;
  const PimDataType t = kType<T>;
  const std::vector<T> a = Values<T>(n, 1), b = Values<T>(n, 2);
  Operands o;
  ASSERT_NO_FATAL_FAILURE(AllocOperands(n, t, a.data(), b.data(), &o));
  const PimObjId oa = o.a, ob = o.b, od = o.d, oc = o.c;
  EXPECT_EQ(Read<T>(oa, n), a);

  auto two = [&](const char* name, PimStatus (*api)(PimObjId, PimObjId, PimObjId), auto ref) {
    ASSERT_EQ(api(oa, ob, od), PIM_OK) << name;
    const std::vector<T> got = Read<T>(od, n);
    for (size_t i = 0; i < n; ++i)
      ASSERT_EQ(got[i], ref(a[i], b[i])) << name << " at " << i << ": " << +a[i] << ", " << +b[i];
  };
  two("pimAdd", pimAdd, [](T x, T y) { return Wrap<T>(U(x) + U(y)); });
  two("pimSub", pimSub, [](T x, T y) { return Wrap<T>(U(x) - U(y)); });
  two("pimMul", pimMul, [](T x, T y) { return Wrap<T>(U(x) * U(y)); });
  two("pimMin", pimMin, [](T x, T y) { return std::min(x, y); });
  two("pimMax", pimMax, [](T x, T y) { return std::max(x, y); });
  two("pimAnd", pimAnd, [](T x, T y) { return T(x & y); });
  two("pimOr", pimOr, [](T x, T y) { return T(x | y); });
  two("pimXor", pimXor, [](T x, T y) { return T(x ^ y); });
  two("pimXnor", pimXnor, [](T x, T y) { return T(~(x ^ y)); });

  auto compare = [&](const char* name, PimStatus (*api)(PimObjId, PimObjId, PimObjId), auto ref) {
    ASSERT_EQ(api(oa, ob, oc), PIM_OK) << name;
    const std::vector<uint8_t> got = Read<uint8_t>(oc, n);
    for (size_t i = 0; i < n; ++i)
      ASSERT_EQ(got[i], ref(W(a[i]), W(b[i])) ? 1 : 0) << name << " at " << i;
  };
  compare("pimGT", pimGT, [](W x, W y) { return x > y; });
  compare("pimLT", pimLT, [](W x, W y) { return x < y; });
  compare("pimEQ", pimEQ, [](W x, W y) { return x == y; });
  compare("pimNE", pimNE, [](W x, W y) { return x != y; });
  // Equal elements too (the vectors above hardly ever are).
  ASSERT_EQ(pimEQ(oa, oa, oc), PIM_OK);
  EXPECT_EQ(Read<uint8_t>(oc, n), std::vector<uint8_t>(n, 1));

  // Division: truncation toward zero; INT64_MIN / -1 wraps to INT64_MIN (C++ leaves it
  // undefined; every narrower type wraps so in int64_t).
  {
    std::vector<T> nz = b;
    for (T& x : nz) if (x == 0) x = T(3);
    nz[5] = T(-1);
    ASSERT_EQ(pimCopyHostToDevice((void*)nz.data(), ob), PIM_OK);
    ASSERT_EQ(pimDiv(oa, ob, od), PIM_OK);
    const std::vector<T> got = Read<T>(od, n);
    for (size_t i = 0; i < n; ++i) {
      T want;
      if (std::is_signed_v<T> && sizeof(T) == 8 && W(a[i]) == std::numeric_limits<W>::min() &&
          W(nz[i]) == W(-1))
        want = a[i];
      else
        want = Wrap<T>(static_cast<uint64_t>(W(a[i]) / W(nz[i])));
      ASSERT_EQ(got[i], want) << "pimDiv at " << i << ": " << +a[i] << " / " << +nz[i];
    }
    ASSERT_EQ(pimCopyHostToDevice((void*)b.data(), ob), PIM_OK);
  }

  auto one = [&](const char* name, PimStatus (*api)(PimObjId, PimObjId), auto ref) {
    ASSERT_EQ(api(oa, od), PIM_OK) << name;
    const std::vector<T> got = Read<T>(od, n);
    for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], ref(a[i])) << name << " at " << i;
  };
  one("pimAbs", pimAbs, [](T x) { return x < 0 ? Wrap<T>(0 - U(x)) : x; });
  one("pimNot", pimNot, [](T x) { return T(~x); });
  one("pimPopCount", pimPopCount,
      [](T x) { return T(std::popcount(static_cast<std::make_unsigned_t<T>>(x))); });

  const uint64_t scalars[] = {0,   1,      3,         ~uint64_t{0}, 200,         300,
                              70000, uint64_t{1} << 63, uint64_t(std::numeric_limits<T>::max())};
  for (const uint64_t s : scalars) {
    SCOPED_TRACE(testing::Message() << "scalar 0x" << std::hex << s);
    const W ws = static_cast<W>(s);
    auto scalar = [&](const char* name, PimStatus (*api)(PimObjId, PimObjId, uint64_t), auto ref) {
      ASSERT_EQ(api(oa, od, s), PIM_OK) << name;
      const std::vector<T> got = Read<T>(od, n);
      for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], ref(a[i])) << name << " at " << i;
    };
    scalar("pimAddScalar", pimAddScalar, [&](T x) { return Wrap<T>(U(x) + s); });
    scalar("pimSubScalar", pimSubScalar, [&](T x) { return Wrap<T>(U(x) - s); });
    scalar("pimMulScalar", pimMulScalar, [&](T x) { return Wrap<T>(U(x) * s); });
    scalar("pimAndScalar", pimAndScalar, [&](T x) { return Wrap<T>(U(x) & s); });
    scalar("pimOrScalar", pimOrScalar, [&](T x) { return Wrap<T>(U(x) | s); });
    scalar("pimXorScalar", pimXorScalar, [&](T x) { return Wrap<T>(U(x) ^ s); });
    scalar("pimXnorScalar", pimXnorScalar, [&](T x) { return Wrap<T>(~(U(x) ^ s)); });
    scalar("pimMinScalar", pimMinScalar,
           [&](T x) { return Wrap<T>(static_cast<uint64_t>(std::min(W(x), ws))); });
    scalar("pimMaxScalar", pimMaxScalar,
           [&](T x) { return Wrap<T>(static_cast<uint64_t>(std::max(W(x), ws))); });
    if (s != 0)
      scalar("pimDivScalar", pimDivScalar, [&](T x) {
        if constexpr (std::is_signed_v<T>)
          if (W(x) == std::numeric_limits<int64_t>::min() && ws == W(-1)) return x;
        return Wrap<T>(static_cast<uint64_t>(W(x) / ws));
      });
    auto cmp = [&](const char* name, PimStatus (*api)(PimObjId, PimObjId, uint64_t), auto ref) {
      ASSERT_EQ(api(oa, oc, s), PIM_OK) << name;
      const std::vector<uint8_t> got = Read<uint8_t>(oc, n);
      for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], ref(W(a[i])) ? 1 : 0) << name << " at " << i;
    };
    cmp("pimGTScalar", pimGTScalar, [&](W x) { return x > ws; });
    cmp("pimLTScalar", pimLTScalar, [&](W x) { return x < ws; });
    cmp("pimEQScalar", pimEQScalar, [&](W x) { return x == ws; });
    cmp("pimNEScalar", pimNEScalar, [&](W x) { return x != ws; });
    ASSERT_EQ(pimScaledAdd(oa, ob, od, s), PIM_OK);
    {
      const std::vector<T> got = Read<T>(od, n);
      for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], Wrap<T>(U(a[i]) * s + U(b[i]))) << i;
    }
    ASSERT_EQ(pimBroadcastInt(od, static_cast<int64_t>(s)), PIM_OK);
    EXPECT_EQ(Read<T>(od, n), std::vector<T>(n, Wrap<T>(s)));
    ASSERT_EQ(pimBroadcastUInt(od, s), PIM_OK);
    EXPECT_EQ(Read<T>(od, n), std::vector<T>(n, Wrap<T>(s)));
  }

  // Bit shifts: arithmetic right for signed types; past the width, 0 or the sign.
  constexpr int bits = 8 * sizeof(T);
  for (unsigned k : {0u, 1u, 3u, unsigned(bits - 1), unsigned(bits), unsigned(bits + 5), 100u}) {
    ASSERT_EQ(pimShiftBitsLeft(oa, od, k), PIM_OK);
    std::vector<T> got = Read<T>(od, n);
    for (size_t i = 0; i < n; ++i)
      ASSERT_EQ(got[i], k >= 64 ? T(0) : Wrap<T>(U(a[i]) << k)) << "left " << k << " at " << i;
    ASSERT_EQ(pimShiftBitsRight(oa, od, k), PIM_OK);
    got = Read<T>(od, n);
    for (size_t i = 0; i < n; ++i) {
      const unsigned kk = std::min(k, 63u);
      const T want = std::is_signed_v<T> ? Wrap<T>(static_cast<uint64_t>(int64_t(W(a[i])) >> kk))
                                         : (k >= 64 ? T(0) : Wrap<T>(U(a[i]) >> k));
      ASSERT_EQ(got[i], want) << "right " << k << " at " << i;
    }
  }

  // Bit slices and conditionals.
  for (unsigned bit : {0u, unsigned(bits / 2), unsigned(bits - 1)}) {
    ASSERT_EQ(pimBitSliceExtract(oa, oc, bit), PIM_OK);
    const std::vector<uint8_t> slice = Read<uint8_t>(oc, n);
    for (size_t i = 0; i < n; ++i) ASSERT_EQ(slice[i], (U(a[i]) >> bit) & 1) << bit << " " << i;
    ASSERT_EQ(pimCopyObjectToObject(ob, od), PIM_OK);
    ASSERT_EQ(pimBitSliceInsert(oc, od, bit), PIM_OK);
    const std::vector<T> got = Read<T>(od, n);
    for (size_t i = 0; i < n; ++i)
      ASSERT_EQ(got[i], Wrap<T>((U(b[i]) & ~(uint64_t{1} << bit)) | (uint64_t(slice[i]) << bit)));
  }
  EXPECT_NE(pimBitSliceExtract(oa, oc, bits), PIM_OK);
  ASSERT_NO_FATAL_FAILURE(
      CheckConditionals<T>(o, a, b, 0x1234567890abcdefull, Wrap<T>(0x1234567890abcdefull)));
  std::vector<T> got;

  // Reductions fold into what the result holds, over ranges at the ends and empty ones.
  struct Range { uint64_t b, e; };
  for (const Range r : {Range{0, 0}, Range{0, n}, Range{n - 1, n}, Range{10, 0}, Range{7, 7},
                        Range{n - 3, n + 10}, Range{0, 1}}) {
    SCOPED_TRACE(testing::Message() << "range [" << r.b << ", " << r.e << ")");
    const uint64_t e = r.e == 0 ? n : std::min<uint64_t>(r.e, n);
    W sum = 5, lo = std::numeric_limits<T>::max(), hi = std::numeric_limits<T>::min();
    for (uint64_t i = r.b; i < e; ++i) {
      sum = static_cast<W>(static_cast<uint64_t>(sum) + U(a[i]));
      lo = std::min<W>(lo, a[i]);
      hi = std::max<W>(hi, a[i]);
    }
    W gotSum = 5;
    ASSERT_EQ(pimRedSum(oa, &gotSum, r.b, r.e), PIM_OK);
    EXPECT_EQ(gotSum, sum);
    T gotMin = std::numeric_limits<T>::max(), gotMax = std::numeric_limits<T>::min();
    ASSERT_EQ(pimRedMin(oa, &gotMin, r.b, r.e), PIM_OK);
    ASSERT_EQ(pimRedMax(oa, &gotMax, r.b, r.e), PIM_OK);
    EXPECT_EQ(gotMin, T(lo));
    EXPECT_EQ(gotMax, T(hi));
  }
  W dummy = 0;
  EXPECT_EQ(pimRedSum(oa, &dummy, n + 1, 0), PIM_ERROR);
  EXPECT_EQ(pimRedSum(oa, &dummy, 9, 4), PIM_ERROR);

  // Prefix sum, element moves.
  ASSERT_EQ(pimPrefixSum(oa, od), PIM_OK);
  got = Read<T>(od, n);
  uint64_t run = 0;
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], Wrap<T>(run += U(a[i]))) << i;
  ASSERT_EQ(pimCopyObjectToObject(oa, od), PIM_OK);
  ASSERT_EQ(pimShiftElementsRight(od), PIM_OK);
  got = Read<T>(od, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], i == 0 ? T(0) : a[i - 1]) << i;
  ASSERT_EQ(pimCopyObjectToObject(oa, od), PIM_OK);
  ASSERT_EQ(pimShiftElementsLeft(od), PIM_OK);
  got = Read<T>(od, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], i + 1 == n ? T(0) : a[i + 1]) << i;
  ASSERT_EQ(pimCopyObjectToObject(oa, od), PIM_OK);
  ASSERT_EQ(pimRotateElementsRight(od), PIM_OK);
  got = Read<T>(od, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], a[(i + n - 1) % n]) << i;
  ASSERT_EQ(pimRotateElementsLeft(od), PIM_OK);
  EXPECT_EQ(Read<T>(od, n), a);

  // Copies with ranges (at the ends, empty), device to device.
  ASSERT_EQ(pimCopyObjectToObject(ob, od), PIM_OK);
  ASSERT_EQ(pimCopyHostToDevice((void*)(a.data() + n - 4), od, n - 4, n), PIM_OK);
  ASSERT_EQ(pimCopyHostToDevice((void*)a.data(), od, 0, 2), PIM_OK);
  ASSERT_EQ(pimCopyHostToDevice((void*)a.data(), od, 9, 9), PIM_OK);
  got = Read<T>(od, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], (i < 2 || i >= n - 4) ? a[i] : b[i]) << i;
  std::vector<T> part(3, T(99));
  ASSERT_EQ(pimCopyDeviceToHost(oa, part.data(), n - 3, n), PIM_OK);
  EXPECT_EQ(part, std::vector<T>(a.end() - 3, a.end()));
  ASSERT_EQ(pimCopyDeviceToDevice(oa, ob, 1, 3), PIM_OK);
  got = Read<T>(ob, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], (i >= 1 && i < 3) ? a[i] : b[i]) << i;
  EXPECT_EQ(pimCopyHostToDevice((void*)a.data(), od, 0, n + 1), PIM_ERROR);
  EXPECT_EQ(pimCopyHostToDevice((void*)a.data(), od, 5, 2), PIM_ERROR);

  for (PimObjId id : {oa, ob, od, oc}) EXPECT_EQ(pimFree(id), PIM_OK);
}

TEST_F(Pim, EveryOperationOnInt8MatchesCpp) { CheckEveryOperation<int8_t>(1000); }
TEST_F(Pim, EveryOperationOnInt16MatchesCpp) { CheckEveryOperation<int16_t>(1000); }
TEST_F(Pim, EveryOperationOnInt32MatchesCpp) { CheckEveryOperation<int32_t>(1000); }
TEST_F(Pim, EveryOperationOnInt64MatchesCpp) { CheckEveryOperation<int64_t>(1000); }
TEST_F(Pim, EveryOperationOnUint8MatchesCpp) { CheckEveryOperation<uint8_t>(1000); }
TEST_F(Pim, EveryOperationOnUint16MatchesCpp) { CheckEveryOperation<uint16_t>(1000); }
TEST_F(Pim, EveryOperationOnUint32MatchesCpp) { CheckEveryOperation<uint32_t>(1000); }
TEST_F(Pim, EveryOperationOnUint64MatchesCpp) { CheckEveryOperation<uint64_t>(1000); }
// More elements than the device's 2048 columns: three layers of PEs.
TEST_F(Pim, EveryOperationOverSeveralLayersMatchesCpp) { CheckEveryOperation<int32_t>(6144); }
// Element moves over several layers need whole layers (the engine's virtual mesh).
TEST_F(Pim, ElementMovesOverPartLayersAreAnErrorNamingTheShape) {
  const PimObjId a = pimAlloc(PIM_ALLOC_AUTO, 5000, PIM_INT32), d = pimAllocAssociated(a, PIM_INT32);
  testing::internal::CaptureStderr();
  EXPECT_EQ(pimPrefixSum(a, d), PIM_ERROR);
  EXPECT_EQ(pimShiftElementsRight(a), PIM_ERROR);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("pimPrefixSum: "), std::string::npos) << err;
  EXPECT_NE(err.find("5000"), std::string::npos) << err;
}

TEST_F(Pim, BoolObjectsAddIntoIntegersAndCount) {
  const size_t n = 700;
  std::vector<uint8_t> f(n), g(n);
  std::vector<int32_t> x(n);
  for (size_t i = 0; i < n; ++i) f[i] = i % 3 == 0, g[i] = i % 5 < 2, x[i] = int32_t(i) - 350;
  const PimObjId ox = pimAlloc(PIM_ALLOC_V, n, PIM_INT32);
  const PimObjId of = pimAllocAssociated(ox, PIM_BOOL), og = pimAllocAssociated(ox, PIM_BOOL);
  const PimObjId oh = pimAllocAssociated(ox, PIM_BOOL);
  ASSERT_EQ(pimCopyHostToDevice(f.data(), of), PIM_OK);
  ASSERT_EQ(pimCopyHostToDevice(g.data(), og), PIM_OK);
  ASSERT_EQ(pimCopyHostToDevice(x.data(), ox), PIM_OK);
  ASSERT_EQ(pimAnd(of, og, oh), PIM_OK);
  std::vector<uint8_t> h = Read<uint8_t>(oh, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(h[i], f[i] & g[i]);
  ASSERT_EQ(pimXor(of, og, oh), PIM_OK);
  h = Read<uint8_t>(oh, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(h[i], f[i] ^ g[i]);
  ASSERT_EQ(pimNot(of, oh), PIM_OK);
  h = Read<uint8_t>(oh, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(h[i], 1 - f[i]);
  uint64_t count = 0;
  ASSERT_EQ(pimRedSum(of, &count), PIM_OK);
  EXPECT_EQ(count, uint64_t(std::count(f.begin(), f.end(), 1)));
  ASSERT_EQ(pimAdd(ox, of, ox), PIM_OK);  // an integer plus a BOOL (PIMeval's accumulation)
  const std::vector<int32_t> y = Read<int32_t>(ox, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(y[i], x[i] + f[i]);
  // pimConvertType: a C++ cast (wrap to a narrower type; to BOOL, nonzero).
  const PimObjId o8 = pimAllocAssociated(ox, PIM_INT8);
  ASSERT_EQ(pimConvertType(ox, o8), PIM_OK);
  const std::vector<int8_t> z = Read<int8_t>(o8, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(z[i], int8_t(y[i]));
  ASSERT_EQ(pimConvertType(ox, oh), PIM_OK);
  h = Read<uint8_t>(oh, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(h[i], y[i] != 0);
}

TEST_F(Pim, AesSboxIsTheTableLookedUpOnTheArray) {
  const size_t n = 600;
  std::vector<uint8_t> lut(256), v(n);
  for (int i = 0; i < 256; ++i) lut[i] = uint8_t(i * 167 + 13);
  for (size_t i = 0; i < n; ++i) v[i] = uint8_t(i * 31);
  const PimObjId a = pimAlloc(PIM_ALLOC_AUTO, n, PIM_UINT8), d = pimAllocAssociated(a, PIM_UINT8);
  ASSERT_EQ(pimCopyHostToDevice(v.data(), a), PIM_OK);
  ASSERT_EQ(pimAesSbox(a, d, lut), PIM_OK);
  std::vector<uint8_t> got = Read<uint8_t>(d, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], lut[v[i]]) << i;
  ASSERT_EQ(pimAesInverseSbox(a, d, lut), PIM_OK);
  EXPECT_EQ(Read<uint8_t>(d, n), got);
  EXPECT_EQ(pimAesSbox(a, d, std::vector<uint8_t>(255)), PIM_ERROR);
}

TEST_F(Pim, DivisionByZeroIsAnErrorAndLeavesTheDestination) {
  std::vector<int32_t> a = {7, -7, 9}, b = {2, 0, 3}, d = {1, 2, 3};
  const PimObjId oa = pimAlloc(PIM_ALLOC_AUTO, 3, PIM_INT32);
  const PimObjId ob = pimAllocAssociated(oa, PIM_INT32), od = pimAllocAssociated(oa, PIM_INT32);
  pimCopyHostToDevice(a.data(), oa);
  pimCopyHostToDevice(b.data(), ob);
  pimCopyHostToDevice(d.data(), od);
  testing::internal::CaptureStderr();
  EXPECT_EQ(pimDiv(oa, ob, od), PIM_ERROR);
  EXPECT_EQ(pimDivScalar(oa, od, 0), PIM_ERROR);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("pimDiv: division by zero"), std::string::npos) << err;
  EXPECT_NE(err.find("pimDivScalar: division by zero"), std::string::npos) << err;
  EXPECT_EQ(Read<int32_t>(od, 3), d);
}

TEST_F(Pim, WhatIsNotSupportedIsAnErrorNamingIt) {
  testing::internal::CaptureStderr();
  EXPECT_EQ(pimAlloc(PIM_ALLOC_AUTO, 10, PIM_BF16), -1);
  EXPECT_EQ(pimAlloc(PIM_ALLOC_H1, 100, PIM_INT32), -1);  // 3200 columns of the device's 2048
  EXPECT_EQ(pimAlloc(PIM_ALLOC_AUTO, 0, PIM_INT32), -1);
  EXPECT_EQ(pimAllocBuffer(10, PIM_INT32), -1);
  const PimObjId a = pimAlloc(PIM_ALLOC_AUTO, 10, PIM_INT32), b = pimAlloc(PIM_ALLOC_AUTO, 10, PIM_INT32);
  const PimObjId c = pimAllocAssociated(a, PIM_INT16);
  EXPECT_EQ(pimAdd(a, b, a), PIM_ERROR);  // not associated
  EXPECT_EQ(pimAdd(a, c, a), PIM_ERROR);  // mixed types
  EXPECT_EQ(pimMAC(a, b, nullptr), PIM_ERROR);
  EXPECT_EQ(pimOpAnd(a, PIM_RREG_R1, PIM_RREG_R2, PIM_RREG_R3), PIM_ERROR);
  EXPECT_EQ(pimFree(12345), PIM_ERROR);
  EXPECT_EQ(pimCreateDevice(PIM_FUNCTIONAL, 1, 1, 1, 1024, 1024), PIM_ERROR);  // one at a time
  // 2048 columns x 1024 rows hold 65,536 INT32 elements at most.
  EXPECT_EQ(pimAlloc(PIM_ALLOC_AUTO, 70000, PIM_INT32), -1);
  const std::string err = testing::internal::GetCapturedStderr();
  for (const char* want :
       {"PIM_BF16", "PIM_ALLOC_H1: 100 elements x 32 column(s) exceed the device's 2048 columns", "at least one element", "pimAllocBuffer", "not associated",
        "is PIM_INT16, expected PIM_INT32", "pimMAC", "pimOpAnd",
        "object id 12345 does not exist", "a device exists already",
        "70000 elements of PIM_INT32 need 2240000 bits; the device holds 2097152"})
    EXPECT_NE(err.find(want), std::string::npos) << want << "\n" << err;
}

TEST(PimDevice, BitParallelAndOtherBitSerialDevicesAreRefused) {
  ::unsetenv("ZEPHYR_MACHINE");
  testing::internal::CaptureStderr();
  for (PimDeviceEnum d : {PIM_DEVICE_FULCRUM, PIM_DEVICE_BANK_LEVEL, PIM_DEVICE_AQUABOLT,
                          PIM_DEVICE_AIM, PIM_DEVICE_BITSIMD_H, PIM_DEVICE_SIMDRAM})
    EXPECT_EQ(pimCreateDevice(d, 1, 1, 1, 1024, 1024), PIM_ERROR);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("PIM_DEVICE_FULCRUM is bit-parallel"), std::string::npos) << err;
  EXPECT_NE(err.find("word-parallel engine"), std::string::npos) << err;
  EXPECT_NE(err.find("PIM_DEVICE_SIMDRAM is a bit-serial design"), std::string::npos) << err;
  PimDeviceProperties p;
  EXPECT_EQ(pimGetDeviceProperties(&p), PIM_ERROR);  // no device was created
}

TEST(PimDevice, PropertiesAreTheGeometryAsked) {
  ::unsetenv("ZEPHYR_MACHINE");
  ASSERT_EQ(pimCreateDevice(PIM_DEVICE_BITSIMD_V_AP, 2, 4, 8, 512, 1024), PIM_OK);
  PimDeviceProperties p;
  ASSERT_EQ(pimGetDeviceProperties(&p), PIM_OK);
  EXPECT_EQ(p.deviceType, PIM_DEVICE_BITSIMD_V_AP);
  EXPECT_EQ(p.simTarget, PIM_DEVICE_BITSIMD_V_AP);
  EXPECT_EQ(p.numRanks, 2u);
  EXPECT_EQ(p.numBankPerRank, 4u);
  EXPECT_EQ(p.numSubarrayPerBank, 8u);
  EXPECT_EQ(p.numRowPerSubarray, 512u);
  EXPECT_EQ(p.numColPerSubarray, 1024u);
  EXPECT_EQ(p.numPIMCores, 64u);
  EXPECT_FALSE(p.isHLayoutDevice);
  EXPECT_EQ(pimDeleteDevice(), PIM_OK);
}

// A temporary file (removed with this).
struct TempFile {
  char path[40] = "/tmp/zephyr_pim_report_XXXXXX";
  TempFile() { ::close(::mkstemp(path)); }
  ~TempFile() { std::remove(path); }
};
// pimShowStats with ZEPHYR_REPORT naming `path`: what it prints.
std::string ShowStats(const char* path) {
  ::setenv("ZEPHYR_REPORT", path, 1);
  testing::internal::CaptureStdout();
  pimShowStats();
  ::unsetenv("ZEPHYR_REPORT");
  return testing::internal::GetCapturedStdout();
}

// The modelled time of one call, from the ZEPHYR_REPORT file pimShowStats writes.
double ModelledMs(const std::string& call, const std::string& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  const std::string text = s.str();
  const size_t at = text.find("\"" + call + "\"");
  if (at == std::string::npos) return -1;
  const size_t ms = text.find("\"modelledMs\":", at);
  return std::stod(text.substr(ms + 13));
}

// An add over the device's columns takes one pass whatever the element count; twice the
// columns take two (PIMeval's regions per core); the copies scale with the bytes.
TEST(PimDevice, ModelledTimeFollowsTheDevicesParallelism) {
  ::unsetenv("ZEPHYR_MACHINE");
  const TempFile report;
  std::vector<double> ms;
  for (uint64_t n : {512, 4096, 8192, 16384}) {
    ASSERT_EQ(pimCreateDevice(PIM_FUNCTIONAL, 1, 1, 2, 256, 4096), PIM_OK);  // 8192 columns
    const PimObjId a = pimAlloc(PIM_ALLOC_AUTO, n, PIM_INT32);
    const PimObjId b = pimAllocAssociated(a, PIM_INT32);
    ASSERT_EQ(pimAdd(a, b, b), PIM_OK);
    const std::string out = ShowStats(report.path);
    EXPECT_NE(out.find("pimAdd INT32"), std::string::npos) << out;
    EXPECT_NE(out.find("by operation"), std::string::npos) << out;  // the cycle report
    ms.push_back(ModelledMs("pimAdd INT32", report.path));
    ASSERT_EQ(pimDeleteDevice(), PIM_OK);
  }
  EXPECT_GT(ms[0], 0);
  EXPECT_DOUBLE_EQ(ms[0], ms[1]);
  EXPECT_DOUBLE_EQ(ms[1], ms[2]);
  EXPECT_DOUBLE_EQ(ms[3], 2 * ms[2]);
}

// A copy between host and device moves its bytes over every rank's channel at once
// (PIMeval: bytes / (rank bandwidth x ranks)): the same elements copied on a device of two
// ranks take half the modelled time of one rank's, and an add over them the same time.
TEST(PimDevice, CopiesShareTheRanksChannels) {
  ::unsetenv("ZEPHYR_MACHINE");
  const TempFile report;
  std::vector<double> copy, add;
  std::vector<int32_t> host(4096, 7);
  for (unsigned ranks : {1u, 2u}) {
    ASSERT_EQ(pimCreateDevice(PIM_FUNCTIONAL, ranks, 1, 2, 256, 4096), PIM_OK);
    const PimObjId a = pimAlloc(PIM_ALLOC_AUTO, host.size(), PIM_INT32);
    const PimObjId b = pimAllocAssociated(a, PIM_INT32);
    ASSERT_EQ(pimCopyHostToDevice(host.data(), a), PIM_OK);
    ASSERT_EQ(pimAdd(a, a, b), PIM_OK);
    ShowStats(report.path);
    copy.push_back(ModelledMs("pimCopyHostToDevice PIM_INT32", report.path));
    add.push_back(ModelledMs("pimAdd INT32", report.path));
    ASSERT_EQ(pimDeleteDevice(), PIM_OK);
  }
  EXPECT_GT(copy[0], 0);
  EXPECT_DOUBLE_EQ(copy[1], copy[0] / 2);
  EXPECT_DOUBLE_EQ(add[1], add[0]);
}

TEST(PimDevice, ZephyrMachineRunsTheProgramOnAnotherProfile) {
  ::setenv("ZEPHYR_MACHINE", "wavetracer", 1);
  ASSERT_EQ(pimCreateDevice(PIM_FUNCTIONAL, 4, 128, 32, 1024, 8192), PIM_OK);
  ::unsetenv("ZEPHYR_MACHINE");
  const size_t n = 20000;  // 3 layers of the WaveTracer's 8192 PEs
  std::vector<int32_t> a(n), b(n);
  for (size_t i = 0; i < n; ++i) a[i] = int32_t(i * 2654435761u), b[i] = int32_t(i) - 7;
  const PimObjId oa = pimAlloc(PIM_ALLOC_AUTO, n, PIM_INT32);
  const PimObjId ob = pimAllocAssociated(oa, PIM_INT32);
  pimCopyHostToDevice(a.data(), oa);
  pimCopyHostToDevice(b.data(), ob);
  ASSERT_EQ(pimAdd(oa, ob, ob), PIM_OK);
  const std::vector<int32_t> c = Read<int32_t>(ob, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(c[i], int32_t(uint32_t(a[i]) + uint32_t(b[i])));
  testing::internal::CaptureStdout();
  pimShowStats();
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("machine profile wavetracer (ZEPHYR_MACHINE)"), std::string::npos) << out;
  EXPECT_NE(out.find("3 virtual-PE layers"), std::string::npos) << out;
  EXPECT_EQ(pimDeleteDevice(), PIM_OK);
}

}  // namespace

// ---- PIM_FP32: IEEE binary32 on the array (MultiFloat), against plain C++ float -----------------
namespace {

// Edge values: signed zeros, NaNs (quiet, negative, signalling with a payload), infinities,
// the largest, the smallest normal and subnormal values, ordinary ones.
std::vector<float> FloatEdges() {
  const float inf = std::numeric_limits<float>::infinity();
  const float mx = std::numeric_limits<float>::max(), mn = std::numeric_limits<float>::min();
  const float dn = std::numeric_limits<float>::denorm_min();
  return {0.0f, -0.0f, 1.0f,  -1.0f, std::numeric_limits<float>::quiet_NaN(), FOf(0xffc00000),
          FOf(0x7fa00001),    inf,   -inf, mx,   -mx,  mn,  -mn,  dn,  -dn,  1.5e-39f, -3e-42f,
          3.0f, 0.1f, 1e30f,  -2.5f, 0.5f, 2.0f, mx / 2, 1.0000001f, 16777216.0f};
}

// Every pair of edge values (a[i], b[i]) first, then random patterns and ordinary values.
void FloatOperands(size_t n, std::vector<float>& a, std::vector<float>& b) {
  const std::vector<float> e = FloatEdges();
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> u(-1000.0f, 1000.0f);
  a.clear(), b.clear();
  for (size_t i = 0; i < n; ++i) {
    if (i < e.size() * e.size()) {
      a.push_back(e[i / e.size()]);
      b.push_back(e[i % e.size()]);
    } else if (i % 2) {
      a.push_back(FOf(rng()));
      b.push_back(FOf(rng()));
    } else {
      a.push_back(u(rng));
      b.push_back(u(rng));
    }
  }
}

// The engine's arithmetic gives IEEE's results bit for bit; a NaN result is the canonical quiet
// NaN 0x7fc00000 (IEEE leaves a NaN result's sign and payload open: x86 propagates an operand's
// payload and gives 0xffc00000 for an invalid operation).
::testing::AssertionResult SameFloat(float got, float want) {
  if (FBits(got) == FBits(want) || (std::isnan(got) && std::isnan(want) && FBits(got) == 0x7fc00000))
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << std::hex << "got 0x" << FBits(got) << " (" << got
                                       << "), want 0x" << FBits(want) << " (" << want << ")";
}

std::vector<uint32_t> Patterns(const std::vector<float>& v) {
  std::vector<uint32_t> r;
  for (float f : v) r.push_back(FBits(f));
  return r;
}

}  // namespace

namespace {
// Every call on PIM_FP32 objects of n elements against plain C++ float.
void CheckEveryFloatOperation(size_t n) {
  SCOPED_TRACE(testing::Message() << "PIM_FP32, " << n << " elements");
  std::vector<float> a, b;
  FloatOperands(n, a, b);
  Operands o;
  ASSERT_NO_FATAL_FAILURE(AllocOperands(n, PIM_FP32, a.data(), b.data(), &o));
  const PimObjId oa = o.a, ob = o.b, od = o.d, oc = o.c;
  EXPECT_EQ(Patterns(Read<float>(oa, n)), Patterns(a));  // every pattern, NaN payloads too

  auto two = [&](const char* name, PimStatus (*api)(PimObjId, PimObjId, PimObjId), auto ref,
                 const std::vector<float>& y) {
    ASSERT_EQ(api(oa, ob, od), PIM_OK) << name;
    const std::vector<float> got = Read<float>(od, n);
    for (size_t i = 0; i < n; ++i)
      ASSERT_TRUE(SameFloat(got[i], ref(a[i], y[i]))) << name << " at " << i << ": " << a[i] << ", " << y[i];
  };
  two("pimAdd", pimAdd, [](float x, float y) { return x + y; }, b);
  two("pimSub", pimSub, [](float x, float y) { return x - y; }, b);
  two("pimMul", pimMul, [](float x, float y) { return x * y; }, b);
  // PIMeval's expressions: the second operand where they compare equal or one is NaN (exact
  // patterns: a selection, no arithmetic).
  auto exact = [&](const char* name, PimStatus (*api)(PimObjId, PimObjId, PimObjId), auto ref) {
    ASSERT_EQ(api(oa, ob, od), PIM_OK) << name;
    const std::vector<float> got = Read<float>(od, n);
    for (size_t i = 0; i < n; ++i)
      ASSERT_EQ(FBits(got[i]), FBits(ref(a[i], b[i]))) << name << " at " << i << ": " << a[i] << ", " << b[i];
  };
  exact("pimMin", pimMin, [](float x, float y) { return x < y ? x : y; });
  exact("pimMax", pimMax, [](float x, float y) { return x > y ? x : y; });
  {
    std::vector<float> nz = b;
    for (float& x : nz) if (x == 0.0f) x = 3.0f;
    ASSERT_EQ(pimCopyHostToDevice((void*)nz.data(), ob), PIM_OK);
    two("pimDiv", pimDiv, [](float x, float y) { return x / y; }, nz);
    ASSERT_EQ(pimCopyHostToDevice((void*)b.data(), ob), PIM_OK);
  }
  auto compare = [&](const char* name, PimStatus (*api)(PimObjId, PimObjId, PimObjId), auto ref) {
    ASSERT_EQ(api(oa, ob, oc), PIM_OK) << name;
    const std::vector<uint8_t> got = Read<uint8_t>(oc, n);
    for (size_t i = 0; i < n; ++i)
      ASSERT_EQ(got[i], ref(a[i], b[i]) ? 1 : 0) << name << " at " << i << ": " << a[i] << ", " << b[i];
  };
  compare("pimGT", pimGT, [](float x, float y) { return x > y; });
  compare("pimLT", pimLT, [](float x, float y) { return x < y; });
  compare("pimEQ", pimEQ, [](float x, float y) { return x == y; });
  compare("pimNE", pimNE, [](float x, float y) { return x != y; });

  ASSERT_EQ(pimAbs(oa, od), PIM_OK);  // PIMeval's (x < 0) ? -x : x: -0 and -NaN keep their sign
  {
    const std::vector<float> got = Read<float>(od, n);
    for (size_t i = 0; i < n; ++i) ASSERT_EQ(FBits(got[i]), FBits(a[i] < 0 ? -a[i] : a[i])) << i;
  }

  const float inf = std::numeric_limits<float>::infinity();
  for (const float s : {1.5f, -0.0f, 0.0f, std::numeric_limits<float>::quiet_NaN(), inf, -inf,
                        std::numeric_limits<float>::max(), std::numeric_limits<float>::denorm_min(),
                        -2.0f, 1e-20f}) {
    SCOPED_TRACE(testing::Message() << "scalar " << s);
    // The scalar is the uint64_t's low 32 bits (PIMeval's castBitsToType<float>).
    const uint64_t bits = (uint64_t{0xdeadbeef} << 32) | FBits(s);
    auto scalar = [&](const char* name, PimStatus (*api)(PimObjId, PimObjId, uint64_t), auto ref,
                      bool exactBits) {
      ASSERT_EQ(api(oa, od, bits), PIM_OK) << name;
      const std::vector<float> got = Read<float>(od, n);
      for (size_t i = 0; i < n; ++i) {
        if (exactBits)
          ASSERT_EQ(FBits(got[i]), FBits(ref(a[i]))) << name << " at " << i << ": " << a[i];
        else
          ASSERT_TRUE(SameFloat(got[i], ref(a[i]))) << name << " at " << i << ": " << a[i];
      }
    };
    scalar("pimAddScalar", pimAddScalar, [&](float x) { return x + s; }, false);
    scalar("pimSubScalar", pimSubScalar, [&](float x) { return x - s; }, false);
    scalar("pimMulScalar", pimMulScalar, [&](float x) { return x * s; }, false);
    if (s != 0.0f) scalar("pimDivScalar", pimDivScalar, [&](float x) { return x / s; }, false);
    else  // +0.0 and -0.0 alike, whatever the high 32 bits of the scalar hold
      EXPECT_EQ(pimDivScalar(oa, od, bits), PIM_ERROR) << "division by " << s;
    scalar("pimMinScalar", pimMinScalar, [&](float x) { return std::min(x, s); }, true);
    scalar("pimMaxScalar", pimMaxScalar, [&](float x) { return std::max(x, s); }, true);
    auto cmp = [&](const char* name, PimStatus (*api)(PimObjId, PimObjId, uint64_t), auto ref) {
      ASSERT_EQ(api(oa, oc, bits), PIM_OK) << name;
      const std::vector<uint8_t> got = Read<uint8_t>(oc, n);
      for (size_t i = 0; i < n; ++i) ASSERT_EQ(got[i], ref(a[i]) ? 1 : 0) << name << " at " << i;
    };
    cmp("pimGTScalar", pimGTScalar, [&](float x) { return x > s; });
    cmp("pimLTScalar", pimLTScalar, [&](float x) { return x < s; });
    cmp("pimEQScalar", pimEQScalar, [&](float x) { return x == s; });
    cmp("pimNEScalar", pimNEScalar, [&](float x) { return x != s; });
    ASSERT_EQ(pimScaledAdd(oa, ob, od, bits), PIM_OK);  // (a * s) + b, two roundings
    {
      const std::vector<float> got = Read<float>(od, n);
      for (size_t i = 0; i < n; ++i) {
        volatile float p = a[i] * s;
        ASSERT_TRUE(SameFloat(got[i], p + b[i])) << "pimScaledAdd at " << i;
      }
    }
    ASSERT_EQ(pimBroadcastFP(od, s), PIM_OK);
    EXPECT_EQ(Patterns(Read<float>(od, n)), std::vector<uint32_t>(n, FBits(s)));
  }

  // Conditionals, copies with ranges, element moves and bit slices move the patterns as they are.
  ASSERT_NO_FATAL_FAILURE(CheckConditionals<float>(o, a, b, FBits(-inf), -inf));
  std::vector<float> got;
  ASSERT_EQ(pimCopyObjectToObject(ob, od), PIM_OK);
  ASSERT_EQ(pimCopyHostToDevice((void*)(a.data() + n - 4), od, n - 4, n), PIM_OK);
  ASSERT_EQ(pimCopyDeviceToDevice(oa, od, 1, 3), PIM_OK);
  got = Read<float>(od, n);
  for (size_t i = 0; i < n; ++i)
    ASSERT_EQ(FBits(got[i]), FBits((i >= 1 && i < 3) || i >= n - 4 ? a[i] : b[i])) << i;
  std::vector<float> part(3);
  ASSERT_EQ(pimCopyDeviceToHost(oa, part.data(), 4, 7), PIM_OK);
  EXPECT_EQ(Patterns(part), Patterns(std::vector<float>(a.begin() + 4, a.begin() + 7)));
  ASSERT_EQ(pimCopyObjectToObject(oa, od), PIM_OK);
  ASSERT_EQ(pimRotateElementsRight(od), PIM_OK);
  got = Read<float>(od, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(FBits(got[i]), FBits(a[(i + n - 1) % n])) << i;
  ASSERT_EQ(pimBitSliceExtract(oa, oc, 31), PIM_OK);  // the sign bits
  const std::vector<uint8_t> sign = Read<uint8_t>(oc, n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(sign[i], FBits(a[i]) >> 31) << i;

  for (PimObjId id : {oa, ob, od, oc}) EXPECT_EQ(pimFree(id), PIM_OK);
}
}  // namespace

TEST_F(Pim, EveryFloatOperationMatchesCppFloatBitForBit) { CheckEveryFloatOperation(1000); }
TEST_F(Pim, EveryFloatOperationOverSeveralLayersMatchesCpp) { CheckEveryFloatOperation(6144); }

namespace {
// PIMeval's pimRedMin/Max on floats (pimCmd.cpp): per region from a seed of FLT_MAX (max:
// lowest) `r = r > x ? x : r`, then `cur = cur > r ? r : cur` into the result; one region here
// (the rule picks the same element over any split into regions).
float PimevalMinMax(const std::vector<float>& v, uint64_t b, uint64_t e, float cur, bool isMin) {
  float r = isMin ? std::numeric_limits<float>::max() : std::numeric_limits<float>::lowest();
  for (uint64_t i = b; i < e; ++i) r = isMin ? (r > v[i] ? v[i] : r) : (r < v[i] ? v[i] : r);
  return isMin ? (cur > r ? r : cur) : (cur < r ? r : cur);
}
// The sum's documented order (docs/pim.md): elements outside [b, e) are +0.0; while s < e,
// element i adds element i + s (+0.0 past the end), s doubling; then cur + (+0.0 + element 0).
float TreeSum(const std::vector<float>& v, uint64_t b, uint64_t e, float cur) {
  std::vector<float> t(v.size(), 0.0f);
  for (uint64_t i = b; i < e; ++i) t[i] = v[i];
  for (uint64_t s = 1; s < e; s *= 2)
    for (uint64_t i = 0; i < t.size(); ++i) t[i] = t[i] + (i + s < t.size() ? t[i + s] : 0.0f);
  return cur + (0.0f + t[0]);
}
// pimRedSum/Min/Max of object o over [b, e) as the call takes it (e 0: to the end), each result
// holding `init` first, against TreeSum and PimevalMinMax of the host's copy v.
void CheckFloatReductions(PimObjId o, const std::vector<float>& v, uint64_t b, uint64_t e,
                          float init) {
  SCOPED_TRACE(testing::Message() << "range [" << b << ", " << e << "), result holding " << init);
  const uint64_t end = e == 0 ? v.size() : std::min<uint64_t>(e, v.size());
  float sum = init, lo = init, hi = init;
  ASSERT_EQ(pimRedSum(o, &sum, b, e), PIM_OK);
  ASSERT_EQ(pimRedMin(o, &lo, b, e), PIM_OK);
  ASSERT_EQ(pimRedMax(o, &hi, b, e), PIM_OK);
  EXPECT_TRUE(SameFloat(sum, TreeSum(v, b, end, init)));
  EXPECT_EQ(FBits(lo), FBits(PimevalMinMax(v, b, end, init, true)));
  EXPECT_EQ(FBits(hi), FBits(PimevalMinMax(v, b, end, init, false)));
}
}  // namespace

TEST_F(Pim, FloatReductionsFollowPimevalOrTheDocumentedTree) {
  const size_t n = 777;
  std::vector<float> a, unused;
  FloatOperands(n, a, unused);
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  // A stretch of +inf only, one of -0/+0 ties, one with a NaN among finite values.
  for (size_t i = 700; i < 705; ++i) a[i] = inf;
  a[710] = 0.0f, a[711] = -0.0f, a[712] = 0.0f;
  a[720] = 5.0f, a[721] = nan, a[722] = -7.0f;
  a[0] = -0.0f;  // [0, 1): a tree of -0.0 alone, then PIMeval's +0.0 seed
  const PimObjId o = pimAlloc(PIM_ALLOC_AUTO, n, PIM_FP32);
  ASSERT_GE(o, 0);
  ASSERT_EQ(pimCopyHostToDevice((void*)a.data(), o), PIM_OK);
  struct Range { uint64_t b, e; };
  for (const Range r : {Range{0, 0}, Range{0, n}, Range{n - 1, n}, Range{10, 0}, Range{7, 7},
                        Range{n - 3, n + 10}, Range{700, 705}, Range{710, 713}, Range{720, 723},
                        Range{600, 700}, Range{0, 1}}) {
    for (const float init : {0.0f, -0.0f, 2.5f, inf, -inf, nan})
      ASSERT_NO_FATAL_FAILURE(CheckFloatReductions(o, a, r.b, r.e, init));
  }
  // Where every partial sum is exact (small integers) the order does not matter: PIMeval's
  // element-by-element sum is the same.
  std::vector<float> ints(n);
  for (size_t i = 0; i < n; ++i) ints[i] = float(int(i % 97) - 40);
  ASSERT_EQ(pimCopyHostToDevice((void*)ints.data(), o), PIM_OK);
  float seq = 0.0f, got = 0.0f;
  for (float x : ints) seq += x;
  ASSERT_EQ(pimRedSum(o, &got), PIM_OK);
  EXPECT_EQ(got, seq);
}

TEST_F(Pim, FloatReductionsOverSeveralLayersAndPartOfOne) {
  // 6144 elements on the fixture's 2048 columns: three layers, the tree's moves cross them.
  const size_t n = 6144;
  std::vector<float> a, unused;
  FloatOperands(n, a, unused);
  const PimObjId o = pimAlloc(PIM_ALLOC_AUTO, n, PIM_FP32);
  ASSERT_GE(o, 0);
  ASSERT_EQ(pimCopyHostToDevice((void*)a.data(), o), PIM_OK);
  for (const uint64_t b : {uint64_t{0}, uint64_t{2000}})
    for (const uint64_t e : {uint64_t{n}, uint64_t{4097}})
      ASSERT_NO_FATAL_FAILURE(CheckFloatReductions(o, a, b, e, 1.0f));
  // Over part of the last layer the elements cannot move along the chain: the host takes every
  // step of the same tree.
  const size_t m = 3000;
  a.resize(m);
  const PimObjId p = pimAlloc(PIM_ALLOC_AUTO, m, PIM_FP32);
  ASSERT_GE(p, 0);
  ASSERT_EQ(pimCopyHostToDevice((void*)a.data(), p), PIM_OK);
  ASSERT_NO_FATAL_FAILURE(CheckFloatReductions(p, a, 3, 2999, 0.5f));
  ASSERT_NO_FATAL_FAILURE(CheckFloatReductions(p, a, 0, 0, -1.0f));
}

TEST_F(Pim, FloatCallsThatDoNotApplyAreErrorsNamingThem) {
  const PimObjId f = pimAlloc(PIM_ALLOC_AUTO, 10, PIM_FP32);
  const PimObjId g = pimAllocAssociated(f, PIM_FP32), i = pimAllocAssociated(f, PIM_INT32);
  const PimObjId c = pimAllocAssociated(f, PIM_BOOL);
  ASSERT_GE(c, 0);
  std::vector<float> v(10, 1.0f);
  v[3] = -0.0f;
  ASSERT_EQ(pimCopyHostToDevice(v.data(), g), PIM_OK);
  ASSERT_EQ(pimCopyHostToDevice(v.data(), f), PIM_OK);
  testing::internal::CaptureStderr();
  EXPECT_EQ(pimAnd(f, g, f), PIM_ERROR);
  EXPECT_EQ(pimXorScalar(f, f, 1), PIM_ERROR);
  EXPECT_EQ(pimNot(f, g), PIM_ERROR);
  EXPECT_EQ(pimPopCount(f, g), PIM_ERROR);
  EXPECT_EQ(pimShiftBitsLeft(f, g, 1), PIM_ERROR);
  EXPECT_EQ(pimPrefixSum(f, g), PIM_ERROR);
  EXPECT_EQ(pimAdd(f, c, f), PIM_ERROR);
  EXPECT_EQ(pimConvertType(f, i), PIM_ERROR);
  EXPECT_EQ(pimConvertType(i, f), PIM_ERROR);
  EXPECT_EQ(pimDiv(f, g, f), PIM_ERROR);  // g holds -0.0
  EXPECT_EQ(pimDivScalar(f, f, FBits(-0.0f)), PIM_ERROR);
  EXPECT_EQ(pimAdd(f, i, f), PIM_ERROR);
  EXPECT_EQ(pimAlloc(PIM_ALLOC_AUTO, 10, PIM_FP16), -1);
  // pimBroadcastFP into an integer object writes the float's pattern (PIMeval's castTypeToBits).
  EXPECT_EQ(pimBroadcastFP(i, -1.5f), PIM_OK);
  EXPECT_EQ(Read<int32_t>(i, 10), std::vector<int32_t>(10, std::bit_cast<int32_t>(-1.5f)));
  const std::string err = testing::internal::GetCapturedStderr();
  for (const char* want :
       {"pimAnd: object 0 is PIM_FP32: bitwise operations", "pimXorScalar: object 0 is PIM_FP32",
        "pimNot: object 0 is PIM_FP32", "pimPopCount: object 0 is PIM_FP32: bit counts",
        "pimShiftBitsLeft: object 0 is PIM_FP32: bit shifts", "pimPrefixSum: object 0 is PIM_FP32",
        "pimAdd: a PIM_BOOL second source", "pimConvertType: PIM_FP32 to PIM_INT32",
        "pimConvertType: PIM_INT32 to PIM_FP32", "pimDiv: division by zero",
        "pimDivScalar: division by zero", "is PIM_INT32, expected PIM_FP32", "PIM_FP16"})
    EXPECT_NE(err.find(want), std::string::npos) << want << "\n" << err;
  // The destination is left as it was.
  EXPECT_EQ(Patterns(Read<float>(f, 10)), Patterns(v));
}

TEST_F(Pim, FloatOperationsAreChargedTheirEngineCycles) {
  const PimObjId f = pimAlloc(PIM_ALLOC_AUTO, 1000, PIM_FP32), g = pimAllocAssociated(f, PIM_FP32);
  const PimObjId i = pimAlloc(PIM_ALLOC_AUTO, 1000, PIM_INT32), j = pimAllocAssociated(i, PIM_INT32);
  ASSERT_GE(g, 0);
  ASSERT_GE(j, 0);
  std::vector<float> ones(1000, 1.0f);
  ASSERT_EQ(pimCopyHostToDevice(ones.data(), g), PIM_OK);
  pimResetStats();
  ASSERT_EQ(pimAdd(f, g, f), PIM_OK);
  ASSERT_EQ(pimAdd(i, j, i), PIM_OK);
  ASSERT_EQ(pimDiv(f, g, f), PIM_OK);
  const TempFile report;
  const std::string out = ShowStats(report.path);
  // The float add costs more than the 32-bit integer add, the division more than the add
  // (restoring, a quotient bit per step); the engine's cycle report names its float operations.
  const double fadd = ModelledMs("pimAdd FP32", report.path);
  const double iadd = ModelledMs("pimAdd INT32", report.path);
  const double fdiv = ModelledMs("pimDiv FP32", report.path);
  EXPECT_GT(iadd, 0);
  EXPECT_GT(fadd, 2 * iadd);
  EXPECT_GT(fdiv, fadd);
  EXPECT_NE(out.find("fadd"), std::string::npos) << out;
  EXPECT_NE(out.find("fdiv"), std::string::npos) << out;
}

// PIMeval accepts the horizontal layouts on its BitSIMD devices: the results are the elements'
// (its functional model), the time the bit-serial table's over the passes the horizontal
// regions take per core: ceil(ceil(n x bits / columns) / cores). The copies ignore the copy type.
TEST(PimDevice, HorizontalLayoutGivesTheSameResultsOverPimevalsPasses) {
  ::unsetenv("ZEPHYR_MACHINE");
  // 1 rank x 1 bank x 4 subarrays x 8192 columns: 4 cores, 32768 columns.
  ASSERT_EQ(pimCreateDevice(PIM_FUNCTIONAL, 1, 1, 4, 1024, 8192), PIM_OK);
  const uint64_t n = 8192;
  std::vector<int32_t> a(n), b(n);
  for (uint64_t k = 0; k < n; ++k) a[k] = int32_t(k * 2654435761u), b[k] = int32_t(k * 40503u + 7);
  const TempFile report;
  std::vector<double> ms;
  for (const PimAllocEnum layout : {PIM_ALLOC_V, PIM_ALLOC_H}) {
    SCOPED_TRACE(layout == PIM_ALLOC_H ? "PIM_ALLOC_H" : "PIM_ALLOC_V");
    const PimObjId x = pimAlloc(layout, n, PIM_INT32), y = pimAllocAssociated(x, PIM_INT32);
    ASSERT_GE(y, 0);
    ASSERT_EQ(pimCopyHostToDeviceWithType(PIM_COPY_H, a.data(), x, 0, 0), PIM_OK);
    ASSERT_EQ(pimCopyHostToDevice(b.data(), y), PIM_OK);
    pimResetStats();
    ASSERT_EQ(pimAdd(x, y, y), PIM_OK);
    ShowStats(report.path);
    ms.push_back(ModelledMs("pimAdd INT32", report.path));
    std::vector<int32_t> got(n);
    ASSERT_EQ(pimCopyDeviceToHostWithType(PIM_COPY_H, y, got.data(), 0, 0), PIM_OK);
    for (uint64_t k = 0; k < n; ++k)
      ASSERT_EQ(got[k], int32_t(uint32_t(a[k]) + uint32_t(b[k]))) << k;
  }
  const double passesV = std::ceil(std::ceil(n / 8192.0) / 4), passesH = std::ceil(std::ceil(n * 32 / 8192.0) / 4);
  EXPECT_EQ(passesH, 8);
  EXPECT_GT(ms[0], 0);
  EXPECT_NEAR(ms[1] / ms[0], passesH / passesV, 1e-9);
  // H1 holds one region per core at most: 1024 INT32 elements fill the 32768 columns.
  EXPECT_GE(pimAlloc(PIM_ALLOC_H1, 1024, PIM_INT32), 0);
  EXPECT_EQ(pimAlloc(PIM_ALLOC_H1, 1025, PIM_INT32), -1);
  EXPECT_EQ(pimCopyHostToDeviceWithType(PimCopyEnum(7), a.data(), 0, 0, 0), PIM_ERROR);
  ASSERT_EQ(pimDeleteDevice(), PIM_OK);
}

// On another profile (ZEPHYR_MACHINE): whole layers of the WaveTracer's 64x128 mesh move along
// the virtual chain; 1000 elements cannot, and the host takes the tree's steps. Same results.
TEST(PimDevice, FloatReductionsRunOnAnotherProfile) {
  ::setenv("ZEPHYR_MACHINE", "wavetracer", 1);
  ASSERT_EQ(pimCreateDevice(PIM_FUNCTIONAL, 1, 1, 1, 1024, 8192), PIM_OK);
  ::unsetenv("ZEPHYR_MACHINE");
  for (const size_t n : {size_t{8192}, size_t{1000}}) {
    SCOPED_TRACE(testing::Message() << n << " elements");
    std::vector<float> a, unused;
    FloatOperands(n, a, unused);
    const PimObjId o = pimAlloc(PIM_ALLOC_AUTO, n, PIM_FP32);
    ASSERT_GE(o, 0);
    ASSERT_EQ(pimCopyHostToDevice((void*)a.data(), o), PIM_OK);
    ASSERT_NO_FATAL_FAILURE(CheckFloatReductions(o, a, 700, 0, 0.0f));
    ASSERT_NO_FATAL_FAILURE(CheckFloatReductions(o, a, 0, 0, 1.0f));
    EXPECT_EQ(pimFree(o), PIM_OK);
  }
  EXPECT_EQ(pimDeleteDevice(), PIM_OK);
}
