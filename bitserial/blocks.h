// bitserial/blocks.h — layer-blocked execution: a program without reductions run block by
// block of virtual-PE layers, the blocks spread over threads (OpenMP).
//
// The emulator otherwise runs each operation over every layer before the next, so at
// hundreds of layers each operation streams the whole plane set through the caches. A
// program whose layers never talk to each other (no reduction; a mesh shift stays inside
// its layer) may instead run whole on a few layers at a time: each block is a Machine that
// holds only its layers (LayerBlock) but models the whole machine, so its PE memory, its
// flags and its cycle report are exactly those of op-by-op execution (the real controller
// ran each instruction once per layer; the report still says so). Reductions on a block
// throw UserError.
//
//   BlockedRun run = RunLayerBlocks(profile, pes, {.blockLayers = 2, .threads = 0},
//                                   [&](Machine& m) { ... m.FirstPe() ... });
//
// Results do not depend on the thread count: each block computes its own PEs only, and the
// caller writes them at FirstPe(). Every block must charge the same instruction stream (the
// program may not branch on its data); RunLayerBlocks checks that the blocks' reports are
// identical and throws std::logic_error if not.
#pragma once

#include <cstdint>
#include <functional>

#include "bitserial/machine.h"
#include "bitserial/memory.h"
#include "bitserial/profile.h"
#include "bitserial/report.h"

namespace zephyr::bitserial {

struct BlockOptions {
  int blockLayers = 0;  // layers per block; 0 = DefaultBlockLayers()
  int threads = 0;      // threads; 0 = every core (HardwareThreads())
  int shapeIndex = 0;   // the mesh shape, as Machine's
};

// Layers per block when none is given: two (the planes of a pass's program on two layers,
// ~2 KB each, stay within a 512 KB L2; docs/bitserial.md, "Layer blocks").
int DefaultBlockLayers();
// The cores OpenMP may use (omp_get_num_procs).
int HardwareThreads();
// The most host threads a run may ask for (--threads): far past any host's cores.
inline constexpr int kMaxThreads = 1024;
// UserError unless 1 <= threads <= kMaxThreads (the --threads flag's check).
int CheckThreads(int threads);

struct BlockedRun {
  CycleReport report;  // the whole machine's (every block's, identical)
  PeMemory memory;     // the PE memory map and peaks (the same in every block)
  int blocks = 0;
  int threads = 0;  // threads used
};

// Runs program(block) for every block of options.blockLayers layers of a machine of
// virtualPes PEs. Blocks run concurrently: the program must touch shared state only at its
// block's own PEs. The first exception (in block order) is rethrown after every block ends.
BlockedRun RunLayerBlocks(const MachineProfile& profile, int64_t virtualPes,
                          const BlockOptions& options,
                          const std::function<void(Machine& block)>& program);

}  // namespace zephyr::bitserial
