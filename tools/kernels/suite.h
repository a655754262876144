// tools/kernels/suite.h — the kernel suite of docs/kernels.md: each kernel of
// tools/kernels/kernels.h (and Life and blur of tools/examples/) with its data, its array
// run (inputs loaded, the program, the result read back), its plain C++ run and the check
// that the two agree bit for bit; one run at a size, timed or not, and the largest size
// that fits a profile's PE memory. build/bin/kernels (tools/kernels/kernels.cpp) prints the
// table; tests/tools/kernels_test.cpp runs every kernel on every profile and target.
#pragma once

#include <fmt/format.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "tools/examples/blur.h"
#include "tools/examples/life.h"
#include "tools/kernels/kernels.h"

namespace zephyr::kernels {

// The built-in profiles whose default mesh is 2-D, which the suite's grid kernels need (the
// era machines; a DRAM PIM array's default is its 1-D row shift, docs/present-day.md): the
// profiles `make kernels` runs when none is named.
inline std::vector<std::string> GridProfiles() {
  std::vector<std::string> names;
  for (const std::string& n : bitserial::ProfileNames())
    if (bitserial::Profile(n).shapes.at(0).extent.size() == 2) names.push_back(n);
  return names;
}

// The 2-D virtual grid of `elements` virtual PEs on profile p's default mesh (P_x × P_y):
// each physical PE holds a b_x × b_y block (b_x·b_y = the layers, b_x = b_y or 2·b_y), so
// 2^20 elements are a 1024 × 1024 grid on both the WaveTracer (64×128) and the MPP
// (128×128). UserError if the mesh is not 2-D or `elements` is not a power-of-two multiple
// of the physical PEs.
inline MeshShape GridFor(const bitserial::MachineProfile& p, int64_t elements) {
  const MeshShape& mesh = p.shapes.at(0);
  if (mesh.extent.size() != 2)
    throw UserError(
        fmt::format("the grid kernels need a 2-D mesh; profile {}'s is {}", p.name, mesh.Name()));
  if (elements < p.physicalPes || elements % p.physicalPes != 0)
    throw UserError(fmt::format("{} elements are not a whole number of {}'s {}-PE layers", elements,
                                p.name, p.physicalPes));
  const int l = Log2Exact(elements / p.physicalPes, "the virtual-PE layers of a grid kernel");
  return MeshShape{{mesh.extent[0] << ((l + 1) / 2), mesh.extent[1] << (l / 2)}};
}

// One kernel: its data, the array program and the plain C++ version of the same result.
class Kernel {
 public:
  virtual ~Kernel() = default;
  virtual std::string Name() const = 0;   // "vadd": the --kernels name
  virtual std::string Title() const = 0;  // "vector add"
  virtual std::string What() const = 0;   // data formats and the program's steps, one line
  // Host data for a machine of `elements` virtual PEs of profile p (UserError if the kernel
  // cannot be laid out at that size, e.g. GridFor's).
  virtual void Prepare(const bitserial::MachineProfile& p, int64_t elements, uint64_t seed) = 0;
  // The array program on m (made for Prepare's elements): the inputs loaded, the program,
  // the result read back — everything it charges to m's report. UserError "PE memory full"
  // if it does not fit.
  virtual void RunArray(bitserial::Machine& m) = 0;
  virtual void RunPlain() = 0;  // the same result in plain C++ from the same inputs
  // "" when the last RunArray's result equals the last RunPlain's bit for bit, else the first
  // difference ("element 17: array 3, plain 4").
  virtual std::string Difference() const = 0;
};

namespace detail {

inline std::string FirstDifference(const std::vector<int64_t>& array,
                                   const std::vector<int64_t>& plain) {
  if (array.size() != plain.size())
    return fmt::format("the array gave {} values, plain C++ {}", array.size(), plain.size());
  for (size_t i = 0; i < array.size(); ++i)
    if (array[i] != plain[i])
      return fmt::format("element {}: array {}, plain C++ {}", i, array[i], plain[i]);
  return "";
}
template <typename T>
std::vector<int64_t> Widen(const std::vector<T>& v) {
  return std::vector<int64_t>(v.begin(), v.end());
}
template <typename T>
std::vector<T> Random(size_t n, std::mt19937_64& rng) {
  std::vector<T> v(n);
  for (auto& x : v) x = static_cast<T>(rng());
  return v;
}

class VectorAddKernel : public Kernel {
 public:
  std::string Name() const override { return "vadd"; }
  std::string Title() const override { return "vector add"; }
  std::string What() const override {
    return "c = a + b on random 32-bit integers (s31.0, wrapping as int32): one add";
  }
  void Prepare(const bitserial::MachineProfile&, int64_t n, uint64_t seed) override {
    std::mt19937_64 rng(seed);
    a_ = Random<int32_t>(n, rng), b_ = Random<int32_t>(n, rng), c_.assign(n, 0);
    rawA_ = Widen(a_), rawB_ = Widen(b_);
  }
  void RunArray(bitserial::Machine& m) override {
    Multi a(m, SignedInt(32), "a"), b(m, SignedInt(32), "b");
    a.LoadRaw(rawA_), b.LoadRaw(rawB_);
    array_ = VectorAdd(a, b).ReadRaw();
  }
  void RunPlain() override { VectorAddPlain(a_, b_, c_); }
  std::string Difference() const override { return FirstDifference(array_, Widen(c_)); }

 private:
  std::vector<int32_t> a_, b_, c_;
  std::vector<int64_t> rawA_, rawB_, array_;
};

class DotKernel : public Kernel {
 public:
  std::string Name() const override { return "dot"; }
  std::string Title() const override { return "dot product"; }
  std::string What() const override {
    return "the exact sum of a_i·b_i over random 16-bit integers: a 32-bit product per PE, "
           "one sum reduction";
  }
  void Prepare(const bitserial::MachineProfile&, int64_t n, uint64_t seed) override {
    std::mt19937_64 rng(seed);
    a_ = Random<int16_t>(n, rng), b_ = Random<int16_t>(n, rng);
    rawA_ = Widen(a_), rawB_ = Widen(b_);
  }
  void RunArray(bitserial::Machine& m) override {
    Multi a(m, SignedInt(16), "a"), b(m, SignedInt(16), "b");
    a.LoadRaw(rawA_), b.LoadRaw(rawB_);
    array_ = DotProduct(a, b).raw.convert_to<int64_t>();
  }
  void RunPlain() override { plain_ = DotProductPlain(a_, b_); }
  std::string Difference() const override {
    return array_ == plain_ ? "" : fmt::format("array {}, plain C++ {}", array_, plain_);
  }

 private:
  std::vector<int16_t> a_, b_;
  std::vector<int64_t> rawA_, rawB_;
  int64_t array_ = 0, plain_ = 1;
};

class MatVecKernel : public Kernel {
 public:
  std::string Name() const override { return "matvec"; }
  std::string Title() const override { return "matrix–vector product"; }
  std::string What() const override {
    return "y = A·x, A of R × C random 16-bit integers on the grid {C, R}, x(c) loaded into "
           "column c: the products, then log2 C shift-and-add steps sum each row into column 0";
  }
  void Prepare(const bitserial::MachineProfile& p, int64_t n, uint64_t seed) override {
    grid_ = GridFor(p, n);
    cols_ = grid_.extent[0], rows_ = grid_.extent[1];
    std::mt19937_64 rng(seed);
    a_ = Random<int16_t>(n, rng), x_ = Random<int16_t>(cols_, rng), y_.assign(rows_, 0);
    rawA_ = Widen(a_), rawX_.resize(n);
    for (int64_t i = 0; i < n; ++i) rawX_[i] = x_[i % cols_];
  }
  void RunArray(bitserial::Machine& m) override {
    Multi a(m, SignedInt(16), "a"), x(m, SignedInt(16), "x");
    a.LoadRaw(rawA_), x.LoadRaw(rawX_);
    const std::vector<int64_t> sums = MatVec(a, x, grid_).ReadRaw();
    array_.resize(rows_);
    for (int r = 0; r < rows_; ++r) array_[r] = sums[size_t(r) * cols_];
  }
  void RunPlain() override { MatVecPlain(a_, x_, rows_, cols_, y_); }
  std::string Difference() const override { return FirstDifference(array_, y_); }

 private:
  MeshShape grid_;
  int rows_ = 0, cols_ = 0;
  std::vector<int16_t> a_, x_;
  std::vector<int64_t> rawA_, rawX_, array_, y_;
};

class HistogramKernel : public Kernel {
 public:
  std::string Name() const override { return "histogram"; }
  std::string Title() const override { return "histogram"; }
  std::string What() const override {
    return "256 bins of random 8-bit values: per bin a compare with a uni and a 1-bit sum "
           "reduction";
  }
  void Prepare(const bitserial::MachineProfile&, int64_t n, uint64_t seed) override {
    std::mt19937_64 rng(seed);
    v_ = Random<uint8_t>(n, rng), raw_ = Widen(v_), counts_.assign(256, 0);
  }
  void RunArray(bitserial::Machine& m) override {
    Multi v(m, UnsignedInt(8), "v");
    v.LoadRaw(raw_);
    array_ = Histogram(v, 256);
  }
  void RunPlain() override { HistogramPlain(v_, counts_); }
  std::string Difference() const override { return FirstDifference(array_, counts_); }

 private:
  std::vector<uint8_t> v_;
  std::vector<int64_t> raw_, array_, counts_;
};

class PrefixSumKernel : public Kernel {
 public:
  std::string Name() const override { return "scan"; }
  std::string Title() const override { return "prefix sum"; }
  std::string What() const override {
    return "inclusive scan of random 8-bit values in row-major order of the grid: rows "
           "scanned along x, row totals along y, spread back along the rows (exact, u8+log2 N)";
  }
  void Prepare(const bitserial::MachineProfile& p, int64_t n, uint64_t seed) override {
    grid_ = GridFor(p, n);
    std::mt19937_64 rng(seed);
    v_ = Random<uint8_t>(n, rng), raw_ = Widen(v_), out_.assign(n, 0);
  }
  void RunArray(bitserial::Machine& m) override {
    Multi v(m, UnsignedInt(8), "v");
    v.LoadRaw(raw_);
    array_ = PrefixSum(v, grid_).ReadRaw();
  }
  void RunPlain() override { PrefixSumPlain(v_, out_); }
  std::string Difference() const override { return FirstDifference(array_, out_); }

 private:
  MeshShape grid_;
  std::vector<uint8_t> v_;
  std::vector<int64_t> raw_, array_, out_;
};

class SortKernel : public Kernel {
 public:
  std::string Name() const override { return "sort"; }
  std::string Title() const override { return "bitonic sort"; }
  std::string What() const override {
    return "random 16-bit keys sorted ascending in row-major order by Batcher's bitonic "
           "network over the grid (log2 N·(log2 N + 1)/2 compare–exchange steps); plain C++: "
           "std::sort";
  }
  void Prepare(const bitserial::MachineProfile& p, int64_t n, uint64_t seed) override {
    grid_ = GridFor(p, n);
    bits_ = Log2Exact(n, "the elements of the bitonic sort");
    std::mt19937_64 rng(seed);
    keys_ = Random<uint16_t>(n, rng), raw_ = Widen(keys_);
  }
  void RunArray(bitserial::Machine& m) override {
    std::vector<Multi> indexBit;
    std::vector<int64_t> bit(raw_.size());
    for (int j = 0; j < bits_; ++j) {
      for (size_t i = 0; i < bit.size(); ++i) bit[i] = (i >> j) & 1;
      indexBit.emplace_back(m, UnsignedInt(1), "indexBit");
      indexBit.back().LoadRaw(bit);
    }
    Multi keys(m, UnsignedInt(16), "keys");
    keys.LoadRaw(raw_);
    array_ = BitonicSort(std::move(keys), grid_, indexBit).ReadRaw();
  }
  void RunPlain() override {
    sorted_ = keys_;
    SortPlain(sorted_);
  }
  std::string Difference() const override { return FirstDifference(array_, Widen(sorted_)); }

 private:
  MeshShape grid_;
  int bits_ = 0;
  std::vector<uint16_t> keys_, sorted_;
  std::vector<int64_t> raw_, array_;
};

class StencilKernel : public Kernel {
 public:
  static constexpr int kSweeps = 8;
  std::string Name() const override { return "stencil"; }
  std::string Title() const override { return "2-D 5-point stencil"; }
  std::string What() const override {
    return fmt::format(
        "{} Jacobi sweeps of out = (4c + n + s + e + w + 4) / 8 over random 8-bit values, 0 "
        "outside the grid: four virtual mesh shifts and four adds per sweep",
        kSweeps);
  }
  void Prepare(const bitserial::MachineProfile& p, int64_t n, uint64_t seed) override {
    grid_ = GridFor(p, n);
    std::mt19937_64 rng(seed);
    g_ = Random<uint8_t>(n, rng), raw_ = Widen(g_);
  }
  void RunArray(bitserial::Machine& m) override {
    Multi g(m, UnsignedInt(8), "g");
    g.LoadRaw(raw_);
    array_ = Stencil5(std::move(g), grid_, kSweeps).ReadRaw();
  }
  void RunPlain() override {
    out_ = g_;
    Stencil5Plain(out_, grid_.extent[0], grid_.extent[1], kSweeps);
  }
  std::string Difference() const override { return FirstDifference(array_, Widen(out_)); }

 private:
  MeshShape grid_;
  std::vector<uint8_t> g_, out_;
  std::vector<int64_t> raw_, array_;
};

class LifeKernel : public Kernel {
 public:
  static constexpr int kGenerations = 8;
  std::string Name() const override { return "life"; }
  std::string Title() const override { return "Conway's Life"; }
  std::string What() const override {
    return fmt::format(
        "{} generations of tools/examples/life.h on a random grid (one cell in three alive)",
        kGenerations);
  }
  void Prepare(const bitserial::MachineProfile& p, int64_t n, uint64_t seed) override {
    grid_ = GridFor(p, n);
    std::mt19937_64 rng(seed);
    cells_.resize(n);
    for (auto& c : cells_) c = rng() % 3 == 0;
  }
  void RunArray(bitserial::Machine& m) override {
    Multi alive(m, UnsignedInt(1), "alive");
    alive.LoadRaw(cells_);
    for (int g = 0; g < kGenerations; ++g) Rebind(alive, examples::LifeStep(alive, grid_));
    array_ = alive.ReadRaw();
  }
  void RunPlain() override {
    plain_ = cells_;
    for (int g = 0; g < kGenerations; ++g)
      plain_ = examples::LifeStepPlain(plain_, grid_.extent[0], grid_.extent[1]);
  }
  std::string Difference() const override { return FirstDifference(array_, plain_); }

 private:
  MeshShape grid_;
  std::vector<int64_t> cells_, array_, plain_;
};

class BlurKernel : public Kernel {
 public:
  std::string Name() const override { return "blur"; }
  std::string Title() const override { return "3×3 blur"; }
  std::string What() const override {
    return "tools/examples/blur.h on random 8-bit pixels: the nine-pixel sum by mesh shifts, "
           "the rounded mean by a division by a uni 9";
  }
  void Prepare(const bitserial::MachineProfile& p, int64_t n, uint64_t seed) override {
    grid_ = GridFor(p, n);
    std::mt19937_64 rng(seed);
    pix_.resize(n);
    for (auto& x : pix_) x = static_cast<int64_t>(rng() % 256);
  }
  void RunArray(bitserial::Machine& m) override {
    Multi p(m, UnsignedInt(8), "p");
    p.LoadRaw(pix_);
    array_ = examples::Blur3x3(p, grid_).ReadRaw();
  }
  void RunPlain() override {
    plain_ = examples::Blur3x3Plain(pix_, grid_.extent[0], grid_.extent[1]);
  }
  std::string Difference() const override { return FirstDifference(array_, plain_); }

 private:
  MeshShape grid_;
  std::vector<int64_t> pix_, array_, plain_;
};

}  // namespace detail

// Every kernel of the suite, in docs/kernels.md's order.
inline std::vector<std::unique_ptr<Kernel>> AllKernels() {
  std::vector<std::unique_ptr<Kernel>> k;
  k.push_back(std::make_unique<detail::VectorAddKernel>());
  k.push_back(std::make_unique<detail::DotKernel>());
  k.push_back(std::make_unique<detail::MatVecKernel>());
  k.push_back(std::make_unique<detail::HistogramKernel>());
  k.push_back(std::make_unique<detail::PrefixSumKernel>());
  k.push_back(std::make_unique<detail::SortKernel>());
  k.push_back(std::make_unique<detail::StencilKernel>());
  k.push_back(std::make_unique<detail::LifeKernel>());
  k.push_back(std::make_unique<detail::BlurKernel>());
  return k;
}

// One run of a kernel at a size.
struct KernelRun {
  std::string kernel, profile;
  std::string target;  // the Highway target the machine's kernels ran on ("AVX2")
  int64_t elements = 0;
  int layers = 0;
  std::string difference;         // "" when the array's result equals plain C++'s bit for bit
  bitserial::CycleReport report;  // the array run's (inputs loaded, program, result read)
  double hostSeconds = 0;         // the array run's wall time on the host, best of its repeats (s)
  double plainSeconds = 0;        // the plain C++ version's, best of its repeats (s)
  std::string note;               // why the size is smaller than asked ("" if it is not)
};

struct RunOptions {
  bool timed = true;  // repeat and time both versions; false: one array run, one plain run
  uint64_t seed = 1;
};

namespace detail {
inline double Seconds(const std::function<void()>& f, int repeats) {
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < repeats; ++i) f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
// The best of a few timings of f per call: calls batched until a batch takes 5 ms (so a
// microsecond baseline is not a clock's resolution), three batches.
inline double BestSeconds(const std::function<void()>& f, double budget) {
  int batch = 1;
  double best = Seconds(f, 1);
  while (best * batch < 0.005 && batch < (1 << 20)) {
    batch *= 2;
    best = Seconds(f, batch) / batch;
  }
  double spent = best * batch;
  for (int i = 0; i < 2 && spent < budget; ++i) {
    const double t = Seconds(f, batch);
    best = std::min(best, t / batch), spent += t;
  }
  return best;
}
}  // namespace detail

// Kernel k at `elements` virtual PEs on `profile`: the array run (timed: the best of up to
// five runs within about 0.3 s), the plain run, the check. UserError from the profile, the
// layout (Prepare) or the machine ("PE memory full" if the program does not fit).
inline KernelRun RunKernel(Kernel& k, const std::string& profile, int64_t elements,
                           const RunOptions& options) {
  KernelRun run;
  run.kernel = k.Name(), run.profile = profile, run.elements = elements;
  const bitserial::MachineProfile p = bitserial::Profile(profile);
  k.Prepare(p, elements, options.seed);
  bitserial::Machine m(p, elements);
  run.layers = m.Layers();
  run.target = m.Kernels().target;
  const auto arrayRun = [&] {
    m.Report().Clear();
    m.ClearFlags();
    k.RunArray(m);
  };
  if (options.timed) {
    run.hostSeconds = detail::Seconds(arrayRun, 1);
    for (int i = 1; i < 5 && i * run.hostSeconds < 0.3; ++i)
      run.hostSeconds = std::min(run.hostSeconds, detail::Seconds(arrayRun, 1));
    run.plainSeconds = detail::BestSeconds([&] { k.RunPlain(); }, 0.1);
  } else {
    arrayRun();
    k.RunPlain();
  }
  run.report = m.Report();
  run.difference = k.Difference();
  return run;
}

// Kernel k at the largest of maxElements, maxElements/2, ... (down to one layer of the
// profile's PEs) whose program fits the profile's PE memory; the note names the next size up,
// which did not fit, and the allocation that failed.
// UserError if maxElements is not a power-of-two multiple of the profile's PEs, or if even
// one layer does not fit.
inline KernelRun RunLargestFitting(Kernel& k, const std::string& profile, int64_t maxElements,
                                   const RunOptions& options) {
  const int pes = bitserial::Profile(profile).physicalPes;
  if (maxElements < pes || maxElements % pes != 0)
    throw UserError(fmt::format("{} elements are not a whole number of {}'s {}-PE layers",
                                maxElements, profile, pes));
  Log2Exact(maxElements / pes, "the virtual-PE layers of the largest size");
  std::string note;
  for (int64_t n = maxElements;; n /= 2) {
    try {
      KernelRun run = RunKernel(k, profile, n, options);
      run.note = note;
      return run;
    } catch (const UserError& e) {
      const std::string what = e.what();
      if (n == pes || what.rfind("PE memory full", 0) != 0) throw;
      note = fmt::format("{} elements do not fit ({})", n, what.substr(0, what.find(';')));
    }
  }
}

}  // namespace zephyr::kernels
