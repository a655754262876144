// bench_bitserial: host speed of the bit-serial engine against a naive
// emulator kept only here (one byte per PE bit, plain loops, as PIMeval stores one bool per
// bit), then host time per modelled cycle against the number of virtual-PE layers, op by op
// and in layer blocks on 1 thread and on every core. The single ops run on every
// Highway target the CPU supports, in the same run, so one machine shows AVX3
// beside AVX2. Prints medians of repeats; not a test. `--help` for the options.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <random>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "bitserial/blocks.h"
#include "bitserial/multi.h"
#include "hwy/targets.h"

using namespace zephyr;
using namespace zephyr::bitserial;
using Clock = std::chrono::steady_clock;

template <typename F>
double MedianSeconds(int repeats, F&& f) {
  std::vector<double> t;
  for (int i = 0; i < repeats; ++i) {
    auto t0 = Clock::now();
    f();
    t.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

// ---- the naive emulator: one byte per bit, bit-major like the planes --------------------
struct NaiveMulti {
  int width;
  std::vector<uint8_t> bits;  // bits[i * pes + pe]
};

void NaiveAdd(const NaiveMulti& a, const NaiveMulti& b, NaiveMulti& out, int pes) {
  for (int pe = 0; pe < pes; ++pe) {
    uint8_t carry = 0;
    for (int i = 0; i < out.width; ++i) {
      uint8_t x = a.bits[i * pes + pe], y = b.bits[i * pes + pe];
      out.bits[i * pes + pe] = x ^ y ^ carry;
      carry = (x & y) | (carry & (x ^ y));
    }
  }
}

// Unsigned shift-and-add, the low out.width bits (enough to time the loops).
void NaiveMul(const NaiveMulti& a, const NaiveMulti& b, NaiveMulti& out, int pes) {
  std::fill(out.bits.begin(), out.bits.end(), 0);
  for (int pe = 0; pe < pes; ++pe)
    for (int j = 0; j < b.width; ++j) {
      uint8_t m = b.bits[j * pes + pe], carry = 0;
      for (int i = 0; i + j < out.width; ++i) {
        uint8_t x = i < a.width ? (a.bits[i * pes + pe] & m) : 0;
        uint8_t acc = out.bits[(i + j) * pes + pe];
        out.bits[(i + j) * pes + pe] = acc ^ x ^ carry;
        carry = (acc & x) | (carry & (acc ^ x));
      }
    }
}

NaiveMulti NaiveFrom(const Multi& m, int pes) {
  NaiveMulti n{m.Width(), std::vector<uint8_t>(static_cast<size_t>(m.Width()) * pes)};
  for (int i = 0; i < m.Width(); ++i)
    for (int pe = 0; pe < pes; ++pe) n.bits[i * pes + pe] = m.BitAt(i, pe);
  return n;
}

// A small per-PE program in the shape of a ray test (multiplies, adds, a square root, a
// compare and a where), narrow enough for 2048 layers' 129 bits per virtual PE.
void LayerProgram(Machine& m) {
  const fixed::Format f = fixed::Format::Signed(3, 8), u = fixed::Format::Unsigned(2, 8);
  std::vector<int64_t> rx(m.VirtualPes()), ry(m.VirtualPes());
  for (int64_t i = 0; i < m.VirtualPes(); ++i) {
    const int64_t pe = m.FirstPe() + i;  // the same data in every blocking
    rx[i] = (pe * 2654435761) % 4096 - 2048;
    ry[i] = (pe * 40503) % 4096 - 2048;
  }
  Multi x(m, f, "x"), y(m, f, "y");
  x.LoadRaw(rx);
  y.LoadRaw(ry);
  Multi best = Broadcast(m, fixed::Fixed{f, 0});
  for (int k = 0; k < 4; ++k) {
    Multi p = Mul(x, y, f);
    Multi s = Add(p, Mul(x, Uni{fixed::FromDouble(0.75 + k, f)}, f), f);
    Multi r = Sqrt(s, u);
    Multi closer = Convert(r, f) < best;
    Where(closer, [&] { best = Convert(r, f); });
  }
  (void)best.ReadRaw();
}

void LayerSweep() {
  fmt::print(
      "\nhost time per modelled cycle against layers (a ray-test-like program; medians of 3;\n"
      "op by op = each op over every layer; blocks of {} layers on 1 thread and on {}):\n",
      DefaultBlockLayers(), HardwareThreads());
  fmt::print("{:>7} {:>14} {:>14} {:>14} {:>14} {:>9}\n", "layers", "cycles", "op-by-op ns/c",
             "blocks 1t ns/c", "blocks Nt ns/c", "Nt/1t");
  const MachineProfile profile = Profile("wavetracer");
  std::vector<double> perCycle1, perCycleN;  // blocks, ns per modelled cycle
  for (int layers : {18, 64, 254, 1024, 2048}) {
    const int64_t pes = int64_t{layers} * profile.physicalPes;
    double cycles = 0;
    double opByOp = 0;
    if (layers <= 254) {  // op by op holds every layer's planes at once
      opByOp = MedianSeconds(3, [&] {
        Machine m(profile, pes);
        LayerProgram(m);
        cycles = m.Report().TotalCycles();
      });
    }
    auto blocked = [&](int threads) {
      return MedianSeconds(3, [&] {
        cycles =
            RunLayerBlocks(profile, pes, {.threads = threads}, LayerProgram).report.TotalCycles();
      });
    };
    const double one = blocked(1), all = blocked(0);
    perCycle1.push_back(one / cycles * 1e9);
    perCycleN.push_back(all / cycles * 1e9);
    fmt::print("{:>7} {:>14.4g} {:>14} {:>14.3f} {:>14.3f} {:>9.2f}\n", layers, cycles,
               opByOp > 0 ? fmt::format("{:.3f}", opByOp / cycles * 1e9) : std::string("-"),
               one / cycles * 1e9, all / cycles * 1e9, one / all);
  }
  auto spread = [](const std::vector<double>& v) {
    return *std::max_element(v.begin(), v.end()) / *std::min_element(v.begin(), v.end());
  };
  fmt::print(
      "flatness (largest / smallest ns per cycle, 18 to 2048 layers; target <= 1.5): "
      "blocks 1t {:.2f}, blocks Nt {:.2f}\n",
      spread(perCycle1), spread(perCycleN));
}

// One target's single ops (the Machine takes the kernel table of the best target hwy
// allows when it is built, so each target gets its own machines). The data come from one
// generator seeded alike for every target: each target multiplies the same numbers.
struct OpTimes {
  int64_t pes;
  double add, mul, mulUni, square, div, sqrt;  // seconds, medians
};

std::vector<OpTimes> SingleOps(const char* target, bool first, bool naive) {
  std::mt19937_64 rng(1);
  const fixed::Format f32 = fixed::Format::Signed(31, 0), f16 = fixed::Format::Signed(15, 0);
  if (first)
    fmt::print("bitserial engine, Highway target {}; single ops on one core\n", target);
  else
    fmt::print(
        "\nHighway target {} (the better ones disabled: hwy::SetSupportedTargetsForTest); "
        "single ops on one core\n",
        target);
  std::vector<OpTimes> times;
  for (int64_t pes : {int64_t{8192}, int64_t{384 * 384}}) {
    Machine m(Profile("wavetracer"), pes);
    if (std::string_view(m.Kernels().target) != target)
      fmt::print("  [the machine took target {}, not {}]\n", m.Kernels().target, target);
    std::vector<int64_t> ra(pes), rb(pes);
    for (auto& x : ra) x = static_cast<int32_t>(rng());
    for (auto& x : rb) x = static_cast<int32_t>(rng());
    Multi a(m, f32, "a"), b(m, f32, "b");
    a.LoadRaw(ra);
    b.LoadRaw(rb);
    for (auto& x : ra) x = static_cast<int16_t>(x);
    for (auto& x : rb) x = static_cast<int16_t>(x);
    Multi a16(m, f16, "a16"), b16(m, f16, "b16");
    a16.LoadRaw(ra);
    b16.LoadRaw(rb);
    const int reps = pes == 8192 ? 2001 : 201;
    m.Report().Clear();
    double tAdd = MedianSeconds(reps, [&] { Multi r = Add(a, b, f32); });
    const double addCycles = m.Report().OpCycles("add") / reps;
    double tMul = MedianSeconds(reps / 4 + 1, [&] { Multi r = Mul(a16, b16, f32); });
    const double mulCycles = m.Report().OpCycles("mul") / (reps / 4 + 1);
    // Division and square root in s15.16 on random 32-bit values (half of the radicands
    // negative; the cycles do not depend on the data).
    const fixed::Format f16_16 = fixed::Format::Signed(15, 16);
    Multi x(m, f16_16, "x"), y(m, f16_16, "y");
    for (auto& v : ra) v = static_cast<int32_t>(rng());
    for (auto& v : rb) v = static_cast<int32_t>(rng());
    x.LoadRaw(ra);
    y.LoadRaw(rb);
    const int divReps = pes == 8192 ? 101 : 11;
    double tDiv = MedianSeconds(divReps, [&] { Multi r = Div(x, y, f16_16); });
    const double divCycles = m.Report().OpCycles("div") / divReps;
    double tSqrt = MedianSeconds(divReps, [&] { Multi r = Sqrt(x, f16_16); });
    const double sqrtCycles = m.Report().OpCycles("sqrt") / divReps;
    // The sphere test's shapes (docs/simd.md): a 21-bit direction component times a 22-bit
    // uni constant, and the square of a 21-bit value, both rounded to 23 bits.
    const fixed::Format f21 = fixed::Format::Signed(10, 10), f23 = fixed::Format::Signed(12, 10);
    Multi d21(m, f21, "d21");
    for (auto& v : ra) v = static_cast<int32_t>(rng()) >> 11;
    d21.LoadRaw(ra);
    const fixed::Fixed k22{fixed::Format::Signed(11, 10),
                           static_cast<int64_t>(static_cast<int32_t>(rng()) >> 10)};
    const int mulReps = pes == 8192 ? 401 : 41;
    double tMulUni = MedianSeconds(mulReps, [&] { Multi r = Mul(d21, Uni{k22}, f23); });
    const double mulUniCycles = m.Report().OpCycles("mulUni") / mulReps;
    double tSquare = MedianSeconds(mulReps, [&] { Multi r = Square(d21, f23); });
    const double squareCycles = m.Report().OpCycles("square") / mulReps;
    const double clock = m.Profile().clockHz;
    fmt::print("\n{} virtual PEs ({} layer{}), profile wavetracer at {:g} Hz\n", pes, m.Layers(),
               m.Layers() == 1 ? "" : "s", clock);
    auto line = [&](const char* name, double seconds, double cycles) {
      fmt::print(
          "  {:<16}: {:9.0f} ns  {:7.0f} machine cycles  {:6.3g} Gcycles/host s  "
          "real-time factor {:.1f}\n",
          name, seconds * 1e9, cycles, cycles / seconds / 1e9, cycles / clock / seconds);
    };
    line("32-bit add", tAdd, addCycles);
    line("16x16 multiply", tMul, mulCycles);
    line("21b x 22b const", tMulUni, mulUniCycles);
    line("21-bit square", tSquare, squareCycles);
    line("s15.16 divide", tDiv, divCycles);
    line("s15.16 sqrt", tSqrt, sqrtCycles);
    times.push_back({pes, tAdd, tMul, tMulUni, tSquare, tDiv, tSqrt});
    if (pes == 8192 && naive) {
      NaiveMulti na = NaiveFrom(a, 8192), nb = NaiveFrom(b, 8192), no = na;
      NaiveMulti na16 = NaiveFrom(a16, 8192), nb16 = NaiveFrom(b16, 8192), no32 = na;
      double nAdd = MedianSeconds(21, [&] { NaiveAdd(na, nb, no, 8192); });
      double nMul = MedianSeconds(5, [&] { NaiveMul(na16, nb16, no32, 8192); });
      // Check the naive add agrees on a PE so the compiler cannot drop it.
      Multi r = Add(a, b, f32);
      bool same = true;
      for (int i = 0; i < 32; ++i) same &= no.bits[i * 8192 + 77] == r.BitAt(i, 77);
      fmt::print(
          "  naive emulator (byte per bit): add {:.0f} ns ({:.0f}x slower), multiply {:.0f} ns "
          "({:.0f}x slower){}\n",
          nAdd * 1e9, nAdd / tAdd, nMul * 1e9, nMul / tMul, same ? "" : "  [MISMATCH]");
    }
  }
  return times;
}

int Usage(int status) {
  fmt::print(status ? stderr : stdout,
             "usage: bench_bitserial [--ops] [--targets NAME,NAME...]\n"
             "  Times single ops on every Highway target this CPU supports (best first; the\n"
             "  others by hwy::SetSupportedTargetsForTest), then a table of them by target, the\n"
             "  naive emulator and the layer sweep on the best target.\n"
             "  --ops      single ops and the table only (no naive emulator, no layer sweep)\n"
             "  --targets  only these targets, e.g. AVX3,AVX2 (names as hwy::TargetName)\n");
  return status;
}

int main(int argc, char** argv) {
  bool opsOnly = false;
  std::vector<std::string> only;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--ops") {
      opsOnly = true;
    } else if (arg == "--targets" && i + 1 < argc) {
      std::string_view list = argv[++i];
      while (!list.empty()) {
        const size_t comma = std::min(list.find(','), list.size());
        only.emplace_back(list.substr(0, comma));
        list.remove_prefix(std::min(comma + 1, list.size()));
      }
    } else {
      return Usage(arg == "--help" || arg == "-h" ? 0 : 2);
    }
  }
  // Every target compiled in and supported here, best first; a Machine built while one is
  // the only supported target runs its kernels.
  std::vector<int64_t> targets;
  for (int64_t t : hwy::SupportedAndGeneratedTargets())
    if (only.empty() || std::find(only.begin(), only.end(), hwy::TargetName(t)) != only.end())
      targets.push_back(t);
  if (targets.empty()) {
    fmt::print(stderr, "bench_bitserial: none of the targets given is supported here\n");
    return 2;
  }
  std::vector<std::vector<OpTimes>> byTarget;
  for (size_t i = 0; i < targets.size(); ++i) {
    hwy::SetSupportedTargetsForTest(targets[i]);
    byTarget.push_back(SingleOps(hwy::TargetName(targets[i]), i == 0, i == 0 && !opsOnly));
  }
  hwy::SetSupportedTargetsForTest(0);
  fmt::print(
      "\nsingle ops by Highway target, ns (medians; one run, the targets one after another):\n");
  fmt::print("{:<28}", "");
  for (int64_t t : targets) fmt::print(" {:>9}", hwy::TargetName(t));
  fmt::print("\n");
  const std::pair<const char*, double OpTimes::*> ops[] = {
      {"32-bit add", &OpTimes::add},         {"16x16 multiply", &OpTimes::mul},
      {"21b x 22b const", &OpTimes::mulUni}, {"21-bit square", &OpTimes::square},
      {"s15.16 divide", &OpTimes::div},      {"s15.16 sqrt", &OpTimes::sqrt}};
  for (size_t k = 0; k < byTarget[0].size(); ++k)
    for (const auto& [name, field] : ops) {
      fmt::print("  {:>6} PEs {:<16}", byTarget[0][k].pes, name);
      for (const auto& times : byTarget) fmt::print(" {:>9.0f}", times[k].*field * 1e9);
      fmt::print("\n");
    }
  if (!opsOnly) LayerSweep();
  return 0;
}
