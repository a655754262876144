// hosts/simd/program.h — the SIMD primary pass's array program (docs/simd.md, "The program",
// "The matrix layout", "Uncertain pixels"): the matrix in external memory, the directions
// loaded from the host, every object's candidate folded into the best hit with the near-tie
// and grazing trackers, the flags, and the matrix read back over the host link. Internal to
// hosts/simd/: the pass (pass.h) runs it in its array passes.
#pragma once

#include <cstdint>
#include <vector>

#include "bitserial/machine.h"
#include "hosts/simd/plan.h"
#include "hosts/trace/tracer.h"

namespace zephyr::simd {

// The matrix as the host reads it (charged to the host link), and the per-PE flags, over
// every PE of the plan (each layer block of each array pass writes its own PEs).
struct MatrixRaw {
  explicit MatrixRaw(int64_t pes)
      : object(pes),
        t(pes),
        d{std::vector<int64_t>(pes), std::vector<int64_t>(pes), std::vector<int64_t>(pes)},
        grazing(pes),
        nearTie(pes),
        overflow(pes) {}
  // Narrow where the value is: an object index (the plan's object format is far below 32
  // bits) and 0/1 flags; at 4096x4096 this is ~0.65 GB instead of ~0.96 GB.
  std::vector<int32_t> object;
  std::vector<int64_t> t, d[3];
  std::vector<uint8_t> grazing, nearTie;
  std::vector<uint8_t> overflow;  // overflow or divide by zero (Invalid: √ of a miss)
};

// The whole program on the machine's PEs (a layer block's own) of the array pass that starts
// at the plan's PE `first`: directions (PE k takes pixel pixels[k], or pixel k when `pixels`
// is empty), every object, flags, and (raw not null) the readout into `raw`.
void RunProgram(bitserial::Machine& m, const PrimaryPlan& plan, const PrimaryRays& rays,
                const std::vector<int64_t>& pixels, int64_t first, MatrixRaw* raw);

// What the program allocates per virtual PE, in bits. Allocation is first fit in program
// order and depends on no PE's values (bitserial/memory.h), so it is the same on every PE,
// layer block and array pass of the same capacities: one virtual PE measures it.
struct ProgramMemory {
  int64_t peakBits = 0;  // the most live at once: internal + external
  int64_t baseBits =
      0;  // live from the directions to the readout: matrix, float directions, trackers
  // Per object (plan order): the most its candidate and fold hold above the base at once.
  std::vector<int64_t> objectBits;
};

// The program run on one virtual PE with `profile`'s PE memory (as one layer's), with no
// readout: UserError (PE memory full) when the program does not fit those capacities.
ProgramMemory MeasureProgram(const PrimaryPlan& plan, const Camera& camera,
                             const bitserial::MachineProfile& profile);

}  // namespace zephyr::simd
