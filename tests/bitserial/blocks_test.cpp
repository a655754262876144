// Layer-blocked execution (bitserial/blocks.h): a program run block by block, on 1, 2 and 4
// threads, gives the same bits, flags, cycle report and memory map as op by op on the whole
// machine; a reduction on a block is refused; a program that branches on its data is caught;
// of several failing blocks the first in block order reports its error.
#include "bitserial/blocks.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "bitserial/multi.h"
#include "fixed/check.h"
#include "fixed/format.h"

namespace zephyr::bitserial {
namespace {

using fixed::Format;

// 4 full layers and a part (the last layer's missing PEs must stay inactive).
constexpr int64_t kPes = 4 * 8192 + 1000;

struct Outcome {
  std::vector<int64_t> r;      // a result per PE, all ops folded in
  std::vector<uint8_t> flags;  // overflow | divideByZero << 1 | invalid << 2, per PE
  std::string report, memory;
};

// A program touching every kind of op (arithmetic with rounding and saturation, where and
// elsewhere, a mesh shift, divide, square root, compare, select) on the PEs [first, first+n)
// of the inputs, writing its outputs at the same place.
void Program(Machine& m, const std::vector<int64_t>& ra, const std::vector<int64_t>& rb,
             Outcome& out) {
  const Format fa = Format::Signed(9, 8), fb = Format::Signed(5, 10), fo = Format::Signed(7, 6);
  const fixed::Policy sat{fixed::Rounding::kNearest, fixed::OverflowPolicy::kSaturate};
  const int64_t first = m.FirstPe(), n = m.VirtualPes();
  Multi a(m, fa, "a"), b(m, fb, "b", Space::kExternal);
  a.LoadRaw(std::vector<int64_t>(ra.begin() + first, ra.begin() + first + n));
  b.LoadRaw(std::vector<int64_t>(rb.begin() + first, rb.begin() + first + n));
  Multi sum = Add(a, b, fo, sat);
  Multi prod = Mul(a, b, fo);
  Multi q = Div(a, b, fo);
  Multi root = Sqrt(a, fo);
  Multi shifted = MeshShift(prod, 1, 3);
  Multi acc = Broadcast(m, fixed::FromDouble(1.5, fo));
  const Multi less = a < b;
  Where(less, [&] { acc = Sub(sum, q, fo, sat); }).Elsewhere([&] { acc = Max(root, shifted, fo); });
  Multi r =
      Select(less, acc, Mul(acc, Uni{fixed::FromDouble(-2.25, Format::Signed(3, 2))}, fo), fo);
  const std::vector<int64_t> raw = r.ReadRaw();
  for (int64_t i = 0; i < n; ++i) {
    out.r[first + i] = raw[i];
    out.flags[first + i] = uint8_t(m.Overflow(i) | m.DivideByZero(i) << 1 | m.Invalid(i) << 2);
  }
}

Outcome Inputs(std::vector<int64_t>& ra, std::vector<int64_t>& rb) {
  std::mt19937_64 rng(11);
  ra.resize(kPes), rb.resize(kPes);
  for (auto& x : ra) x = static_cast<int64_t>(rng()) >> (64 - 18);
  for (auto& x : rb) x = static_cast<int64_t>(rng()) >> (64 - 16);
  for (int64_t i = 0; i < kPes; i += 97) rb[i] = 0;  // some divisions by zero
  Outcome o;
  o.r.assign(kPes, 0);
  o.flags.assign(kPes, 0);
  return o;
}

TEST(BitserialBlocks, SameBitsFlagsAndReportAsOpByOpForAnyBlockAndThreadCount) {
  std::vector<int64_t> ra, rb;
  Outcome whole = Inputs(ra, rb);
  {
    Machine m(Profile("wavetracer"), kPes);
    ASSERT_EQ(m.Layers(), 5);
    Program(m, ra, rb, whole);
    whole.report = m.Report().Json().dump();
    whole.memory = m.Memory().Map();
  }
  int flagged = 0;
  for (uint8_t f : whole.flags) flagged += f != 0;
  ASSERT_GT(flagged, 0);  // the comparison covers the flags too
  for (int blockLayers : {1, 2, 3}) {
    for (int threads : {1, 2, 4}) {
      Outcome blocked = Inputs(ra, rb);
      const BlockedRun run = RunLayerBlocks(Profile("wavetracer"), kPes, {blockLayers, threads},
                                            [&](Machine& m) { Program(m, ra, rb, blocked); });
      const std::string what =
          fmt::format("{} layer(s) per block, {} thread(s)", blockLayers, threads);
      EXPECT_EQ(run.blocks, (5 + blockLayers - 1) / blockLayers) << what;
      EXPECT_EQ(blocked.r, whole.r) << what;
      EXPECT_EQ(blocked.flags, whole.flags) << what;
      EXPECT_EQ(run.report.Json().dump(), whole.report) << what;
      EXPECT_EQ(run.memory.Map(), whole.memory) << what;
    }
  }
}

TEST(BitserialBlocks, ABlockModelsTheWholeMachine) {
  Machine m(Profile("wavetracer"), kPes, 0, LayerBlock{4, 1});
  EXPECT_TRUE(m.IsBlock());
  EXPECT_EQ(m.Layers(), 1);
  EXPECT_EQ(m.ModelledLayers(), 5);
  EXPECT_EQ(m.FirstPe(), 4 * 8192);
  EXPECT_EQ(m.VirtualPes(), 1000);
  EXPECT_EQ(m.Memory().Capacity(Space::kInternal), 2048 / 5);
  EXPECT_THROW(Machine(Profile("wavetracer"), kPes, 0, LayerBlock{5, 1}), UserError);
}

TEST(BitserialBlocks, ReductionOnABlockIsRefused) {
  Machine m(Profile("wavetracer"), kPes, 0, LayerBlock{1, 2});
  Multi a(m, Format::Signed(3, 0), "a");
  try {
    ReduceMax(a);
    FAIL() << "no error";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("layers 1..2 of 5"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Any(a < a), UserError);
  EXPECT_THROW(ReduceSum(a), UserError);
}

TEST(BitserialBlocks, AProgramThatBranchesOnItsDataIsCaught) {
  // Block 1 runs one more add than block 0: its instruction stream differs.
  EXPECT_THROW(RunLayerBlocks(Profile("wavetracer"), kPes, {1, 2},
                              [](Machine& m) {
                                Multi a(m, Format::Signed(3, 0), "a");
                                if (m.FirstLayer() == 1) Multi b = a + a;
                              }),
               std::logic_error);
  // Control: the same blocks without the branch pass.
  EXPECT_NO_THROW(RunLayerBlocks(Profile("wavetracer"), kPes, {1, 2}, [](Machine& m) {
    Multi a(m, Format::Signed(3, 0), "a");
    Multi b = a + a;
  }));
  EXPECT_THROW(CheckThreads(0), UserError);
}

// A program that fails in two blocks (those holding layers 1 and 3 of 5): the error
// rethrown is the first failing block's in block order, for 1, 2 and 4 threads and every
// block size, and every block has run to its end before it is. The earlier block fails
// 100 ms late and with another exception type, so an error taken in the order the threads
// meet them (the later block's, on 2 or 4 threads) or the last in block order is caught.
TEST(BitserialBlocks, TheErrorOfTwoFailingBlocksIsTheFirstInBlockOrder) {
  for (int blockLayers : {1, 2, 3}) {
    const int blocks = (5 + blockLayers - 1) / blockLayers;
    // The first block holding layer 1 (the first failure in block order).
    const int firstFailing = 1 / blockLayers;
    for (int threads : {1, 2, 4}) {
      const std::string what =
          fmt::format("{} layer(s) per block, {} thread(s)", blockLayers, threads);
      std::vector<int> ran(blocks, 0);
      try {
        RunLayerBlocks(Profile("wavetracer"), kPes, {blockLayers, threads}, [&](Machine& m) {
          Multi a(m, Format::Signed(3, 0), "a");
          Multi b = a + a;
          const int first = m.FirstLayer(), last = first + m.Layers() - 1;
          ran[first / blockLayers] = 1;
          if (first <= 1 && 1 <= last) {
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
            throw UserError(fmt::format("failed in the block at layer {}", first));
          }
          if (first <= 3 && 3 <= last)
            throw std::runtime_error(fmt::format("failed in the block at layer {}", first));
        });
        ADD_FAILURE() << "no error, " << what;
      } catch (const UserError& e) {
        EXPECT_EQ(std::string(e.what()),
                  fmt::format("failed in the block at layer {}", firstFailing * blockLayers))
            << what;
      } catch (const std::exception& e) {
        ADD_FAILURE() << "the later block's error: " << e.what() << ", " << what;
      }
      EXPECT_EQ(ran, std::vector<int>(blocks, 1)) << "every block ran, " << what;
    }
  }
}

}  // namespace
}  // namespace zephyr::bitserial
