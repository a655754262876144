// bitserial/report.h — cycles charged by a program, by class, by operation and by layer.
//
// Every virtual-PE layer runs the same instruction stream (SIMD), so each layer is
// charged the same cycles; the total is the per-layer figure × the number of layers, and
// the report lists the layers so a reader sees where the time goes.
#pragma once

#include <array>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "bitserial/cost.h"
#include "bitserial/profile.h"

namespace zephyr::bitserial {

class CycleReport {
 public:
  // Keeps its own copy of the profile, so a report outlives its machine (a layer block's
  // report is the whole machine's, bitserial/blocks.h).
  CycleReport(const MachineProfile* profile, int layers);
  // A sum of no runs (no profile yet): the first Add takes its profile.
  CycleReport() = default;

  // Charges one call of `op` whose per-layer micro-op counts are `counts`.
  void Charge(const std::string& op, const MicroOpCounts& counts);
  // Charges one call of `op` whose micro-ops differ from layer to layer (a move across the
  // virtual mesh, multi.h): `total` is summed over every layer, not per layer.
  void ChargeWhole(const std::string& op, const MicroOpCounts& total);
  void Clear();
  // The same calls and micro-op counts of every op (the same instruction stream).
  bool SameCharges(const CycleReport& other) const;
  // Charge, ChargeWhole, Clear and SameCharges are for the report of one run of a program (a
  // machine's); a sum of runs (Add) is read, not charged (ZEPHYR_CHECK).

  // This report plus `other`'s runs after its own: a program run several times (the SIMD
  // pass's array passes) reported as one. Totals, classes and ops are summed run by run;
  // the layers are listed run after run. The profiles must be the same (ZEPHYR_CHECK),
  // unless either report is empty (default-constructed: an empty `other` adds nothing).
  void Add(const CycleReport& other);
  int Runs() const { return int(runs_.size()); }  // runs summed (1 unless Add was called)
  CycleReport Run(int k) const;                   // the k-th run's own report, 0 <= k < Runs()
  const MachineProfile& Profile() const { return profile_; }

  int Layers() const;          // over every run
  double LayerCycles() const;  // one layer's instruction stream (one run only: ZEPHYR_CHECK)
  double TotalCycles() const;
  double ClassCycles(CycleClass c) const;
  // Total cycles charged to `op` over all layers (0 if never charged) and its call count.
  double OpCycles(const std::string& op) const;
  int64_t OpCalls(const std::string& op) const;
  double ModelledSeconds() const;  // at the profile's clock, summed run by run

  // {"profile", "clockHz", "layers", "totalCycles", "modelledSeconds", "byClass": {...},
  //  "byLayer": [...], "byOp": {"add": {"calls", "cycles", "byClass", "microOps"}}}; a sum of
  // several runs gives each layer's run too ("byLayer": [{"layer", "pass", "cycles"}]).
  nlohmann::json Json() const;
  // One run's table (a sum's is each run's table: see Run).
  std::string Table() const;

 private:
  struct OpStats {
    int64_t calls = 0;
    MicroOpCounts counts;  // per layer
    MicroOpCounts whole;   // over all layers (ChargeWhole)
    std::array<double, kCycleClassCount> byClass{};
  };
  // One run of a program: every layer charged the same (per layer, times `layers`).
  struct ProgramRun {
    int layers = 0;
    std::array<double, kCycleClassCount> byClass{};  // per layer
    std::map<std::string, OpStats> ops{};            // per layer
    double LayerCycles() const;
    double TotalCycles() const { return LayerCycles() * layers; }
  };
  ProgramRun& Single();
  const ProgramRun& Single() const;

  MachineProfile profile_;
  std::vector<ProgramRun> runs_;  // one, or the runs Add summed
};

}  // namespace zephyr::bitserial
