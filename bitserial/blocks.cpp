#include "bitserial/blocks.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <exception>
#include <optional>
#include <stdexcept>
#include <vector>

#include "fixed/check.h"

namespace zephyr::bitserial {

int DefaultBlockLayers() { return 2; }

int HardwareThreads() { return std::max(1, omp_get_num_procs()); }

int CheckThreads(int threads) {
  if (threads < 1 || threads > kMaxThreads)
    throw UserError(fmt::format("host threads must be 1..{}, got {}", kMaxThreads, threads));
  return threads;
}

BlockedRun RunLayerBlocks(const MachineProfile& profile, int64_t virtualPes,
                          const BlockOptions& options,
                          const std::function<void(Machine& block)>& program) {
  const int64_t pes = virtualPes == 0 ? profile.physicalPes : virtualPes;
  if (pes < 0) throw UserError(fmt::format("virtual PEs must be >= 0, got {}", virtualPes));
  if (options.blockLayers < 0)
    throw UserError(fmt::format("layer blocks of {} layers", options.blockLayers));
  const int layers = static_cast<int>((pes + profile.physicalPes - 1) / profile.physicalPes);
  const int per =
      std::min(layers, options.blockLayers > 0 ? options.blockLayers : DefaultBlockLayers());
  const int blocks = (layers + per - 1) / per;
  const int threads =
      std::min(blocks, options.threads > 0 ? CheckThreads(options.threads) : HardwareThreads());

  // Block 0 keeps its report and memory; every other block's report is compared with it.
  std::vector<std::optional<CycleReport>> reports(blocks);
  std::vector<std::exception_ptr> errors(blocks);
  std::optional<PeMemory> memory;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int b = 0; b < blocks; ++b) {
    try {
      const LayerBlock block{b * per, std::min(per, layers - b * per)};
      Machine m(profile, pes, options.shapeIndex, block);
      program(m);
      reports[b].emplace(m.Report());
      if (b == 0) memory.emplace(m.Memory());
    } catch (...) {
      errors[b] = std::current_exception();
    }
  }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  for (int b = 1; b < blocks; ++b)
    if (!reports[b]->SameCharges(*reports[0]))
      throw std::logic_error(fmt::format(
          "layer block {} charged another instruction stream than block 0: the program branches "
          "on its data and cannot run in layer blocks",
          b));
  return BlockedRun{*reports[0], *memory, blocks, threads};
}

}  // namespace zephyr::bitserial
