// tools/kernels/kernels.h — the classic SIMD-array kernels as programs for the emulated
// Zephyr (docs/kernels.md; the patterns are taught in docs/programming.md): vector add, dot
// product, matrix–vector product, histogram, prefix sum, bitonic sort and a 2-D 5-point
// stencil, each beside the same computation in plain C++. The array programs use only the
// installed API (bitserial/multi.h), as a user's program would; Life and blur are
// tools/examples/. tools/kernels/suite.h runs them on data, checks and times them.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "bitserial/multi.h"
#include "fixed/check.h"

namespace zephyr::kernels {

using bitserial::MeshShape;
using bitserial::Multi;
using bitserial::Uni;

// An n-bit two's-complement integer format (s(n-1).0) and an n-bit unsigned one (un.0).
inline fixed::Format SignedInt(int bits) { return fixed::Format::Signed(bits - 1, 0); }
inline fixed::Format UnsignedInt(int bits) { return fixed::Format::Unsigned(bits, 0); }

// v becomes `next`, whatever the formats (assignment would convert `next` into v's format
// and charge a copy; a loop whose value widens each step rebinds instead).
inline void Rebind(Multi& v, Multi next) { std::swap(v, next); }

// log2 of a power of two; UserError naming `what` otherwise.
inline int Log2Exact(int64_t n, const char* what) {
  int k = 0;
  while ((int64_t{1} << k) < n) ++k;
  if (n < 1 || (int64_t{1} << k) != n)
    throw UserError(std::string(what) + " must be a power of two, got " + std::to_string(n));
  return k;
}

// ---- vector add: c = a + b on 32-bit integers, wrapping as C++'s int32 arithmetic ----------
// One add per element pair: the bit-serial add of 32 bits (4n + 2 cycles on the WaveTracer,
// docs/bitserial.md).
inline Multi VectorAdd(const Multi& a, const Multi& b) { return Add(a, b, SignedInt(32)); }
inline void VectorAddPlain(const std::vector<int32_t>& a, const std::vector<int32_t>& b,
                           std::vector<int32_t>& c) {
  for (size_t i = 0; i < a.size(); ++i)
    c[i] = static_cast<int32_t>(static_cast<uint32_t>(a[i]) + static_cast<uint32_t>(b[i]));
}

// ---- dot product: the exact sum of a_i·b_i over 16-bit integers ----------------------------
// A product in every PE, then one sum reduction to the host (bit-serial: one count per bit
// of the product, weighted by the host).
inline fixed::Fixed DotProduct(const Multi& a, const Multi& b) { return ReduceSum(a * b); }
inline int64_t DotProductPlain(const std::vector<int16_t>& a, const std::vector<int16_t>& b) {
  int64_t s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += int32_t{a[i]} * int32_t{b[i]};
  return s;
}

// ---- matrix–vector product: y = A·x, A of R rows and C columns ------------------------------
// A's element (r, c) in virtual PE c + C·r of the grid {C, R}; x(c) in every PE of column c.
// The products, then each row summed into its column 0 by recursive doubling along x
// (log2 C shifts and adds, each step one bit wider; docs/programming.md, "Reductions").
// Returns the multi whose column 0 holds y.
inline Multi RowSumsToColumnZero(Multi s, const MeshShape& grid) {
  for (int d = 1; d < grid.extent[0]; d *= 2) Rebind(s, s + MeshShift(s, grid, 0, -d));
  return s;
}
inline Multi MatVec(const Multi& a, const Multi& xRepeated, const MeshShape& grid) {
  return RowSumsToColumnZero(a * xRepeated, grid);
}
inline void MatVecPlain(const std::vector<int16_t>& a, const std::vector<int16_t>& x, int rows,
                        int cols, std::vector<int64_t>& y) {
  for (int r = 0; r < rows; ++r) {
    int64_t s = 0;
    for (int c = 0; c < cols; ++c) s += int32_t{a[size_t(r) * cols + c]} * int32_t{x[c]};
    y[r] = s;
  }
}

// ---- histogram of 8-bit values into 256 bins ----------------------------------------------
// Per bin: compare every element with the bin's value (a uni), count the 1s (a 1-bit sum
// reduction): 256 compares and 256 one-bit reductions whatever the element count.
inline std::vector<int64_t> Histogram(const Multi& v, int bins) {
  std::vector<int64_t> counts(bins);
  for (int b = 0; b < bins; ++b)
    counts[b] = ReduceSum(Equal(v, Uni{fixed::Fixed{v.Format(), b}})).raw.convert_to<int64_t>();
  return counts;
}
inline void HistogramPlain(const std::vector<uint8_t>& v, std::vector<int64_t>& counts) {
  std::fill(counts.begin(), counts.end(), 0);
  for (uint8_t x : v) ++counts[x];
}

// ---- prefix sum (inclusive scan) over a 2-D grid in row-major order --------------------------
// Hillis–Steele scans over the virtual mesh (docs/programming.md, "Scans"): each row scanned
// along x (log2 X shift-and-add steps), the row totals (column X-1) scanned along y, moved
// one row down (the rows before each row) and spread back along the row, then added. The
// mesh distances sum to about 2X + Y per bit, not the N of a scan along one long chain.
// `v` is unsigned; the result has log2 N more bits, exact.
inline Multi PrefixSum(const Multi& v, const MeshShape& grid) {
  const int X = grid.extent[0], Y = grid.extent[1];
  Multi row = v + MeshShift(v, grid, 0, 1);  // inclusive scan of each row
  for (int d = 2; d < X; d *= 2) Rebind(row, row + MeshShift(row, grid, 0, d));
  // The last column, from the edge rule: a shift by -1 brings 0 into x = X-1 only.
  const Multi one = Broadcast(v.GetMachine(), fixed::Fixed{UnsignedInt(1), 1});
  const Multi lastColumn = Not(MeshShift(one, grid, 0, -1));
  const Multi zero = Broadcast(v.GetMachine(), fixed::Fixed{row.Format(), 0});
  Multi totals = Select(lastColumn, row, zero, row.Format());
  for (int d = 1; d < Y; d *= 2) Rebind(totals, totals + MeshShift(totals, grid, 1, d));
  Multi before = MeshShift(totals, grid, 1, 1);  // rows above: a sum of whole rows, in column X-1
  // Spread column X-1 along each row: the other columns hold 0, so the adds never carry
  // past the format.
  for (int d = 1; d < X; d *= 2)
    Rebind(before, Add(before, MeshShift(before, grid, 0, -d), before.Format()));
  return Add(row, before, before.Format());
}
inline void PrefixSumPlain(const std::vector<uint8_t>& v, std::vector<int64_t>& out) {
  int64_t s = 0;
  for (size_t i = 0; i < v.size(); ++i) out[i] = s += v[i];
}

// ---- bitonic sort over a 2-D grid (ascending in row-major order) ----------------------------
// Batcher's network: stage k (1..n, N = 2^n) merges blocks of 2^k, step j (k-1..0) compares
// element i with i ^ 2^j, which is 2^j along x for j < log2 X, else 2^(j - log2 X) along y.
// indexBit[j] is bit j of each PE's row-major index (1-bit multis loaded once: the cost of
// loading the index itself). Per step: the partner from both sides (two virtual mesh shifts,
// a select on indexBit[j]), min and max, a select on the direction (docs/programming.md,
// "Sorting networks on a mesh").
inline Multi BitonicSort(Multi keys, const MeshShape& grid, const std::vector<Multi>& indexBit) {
  const int n = static_cast<int>(indexBit.size());
  const int logX = Log2Exact(grid.extent[0], "the grid's x extent");
  const fixed::Format f = keys.Format();
  for (int k = 1; k <= n; ++k)
    for (int j = k - 1; j >= 0; --j) {
      const int axis = j < logX ? 0 : 1;
      const int d = 1 << (j < logX ? j : j - logX);
      const Multi& upper = indexBit[j];  // this PE is the pair's upper element
      const Multi partner =
          Select(upper, MeshShift(keys, grid, axis, d), MeshShift(keys, grid, axis, -d), f);
      // A block whose bit k is set sorts descending; the last stage (k = n) ascends.
      const Multi takeMax = k < n ? Xor(upper, indexBit[k]) : upper;
      Rebind(keys, Select(takeMax, Max(keys, partner, f), Min(keys, partner, f), f));
    }
  return keys;
}
inline void SortPlain(std::vector<uint16_t>& v) { std::sort(v.begin(), v.end()); }

// ---- 2-D 5-point stencil (Jacobi sweeps) on 8-bit values ------------------------------------
// Each sweep: out = (4·c + n + s + e + w) / 8 rounded to nearest (halves up), cells outside
// the grid 0: four virtual mesh shifts, four adds in u11.0, one shift.
inline Multi Stencil5(Multi g, const MeshShape& grid, int sweeps) {
  const fixed::Format sum = UnsignedInt(11);  // 8 × 255 = 2040
  for (int s = 0; s < sweeps; ++s) {
    Multi acc = Add(Shift(g, 2, sum), MeshShift(g, grid, 0, 1), sum);
    Rebind(acc, Add(acc, MeshShift(g, grid, 0, -1), sum));
    Rebind(acc, Add(acc, MeshShift(g, grid, 1, 1), sum));
    Rebind(acc, Add(acc, MeshShift(g, grid, 1, -1), sum));
    Rebind(g, Shift(acc, -3, g.Format(), {fixed::Rounding::kNearest}));
  }
  return g;
}
inline void Stencil5Plain(std::vector<uint8_t>& g, int w, int h, int sweeps) {
  std::vector<uint8_t> next(g.size());
  for (int s = 0; s < sweeps; ++s) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        int sum = 4 * g[i];
        if (x > 0) sum += g[i - 1];
        if (x + 1 < w) sum += g[i + 1];
        if (y > 0) sum += g[i - w];
        if (y + 1 < h) sum += g[i + w];
        next[i] = static_cast<uint8_t>((sum + 4) >> 3);
      }
    g.swap(next);
  }
}

}  // namespace zephyr::kernels
