// bitserial/report.h — cycles charged by a program, by class, by operation and by layer.
//
// Every virtual-PE layer runs the same instruction stream (SIMD), so each layer is
// charged the same cycles; the total is the per-layer figure × the number of layers, and
// the report lists the layers so a reader sees where the time goes.
#pragma once

#include <array>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "bitserial/cost.h"
#include "bitserial/profile.h"

namespace zephyr::bitserial {

class CycleReport {
 public:
  // Keeps its own copy of the profile, so a report outlives its machine (a layer block's
  // report is the whole machine's, bitserial/blocks.h).
  CycleReport(const MachineProfile* profile, int layers) : profile_(*profile), layers_(layers) {}

  // Charges one call of `op` whose per-layer micro-op counts are `counts`.
  void Charge(const std::string& op, const MicroOpCounts& counts);
  // Charges one call of `op` whose micro-ops differ from layer to layer (a move across the
  // virtual mesh, multi.h): `total` is summed over every layer, not per layer.
  void ChargeWhole(const std::string& op, const MicroOpCounts& total);
  void Clear();
  // The same calls and micro-op counts of every op (the same instruction stream).
  bool SameCharges(const CycleReport& other) const;

  int Layers() const { return layers_; }
  double LayerCycles() const;  // one layer's instruction stream
  double TotalCycles() const { return LayerCycles() * layers_; }
  double ClassCycles(CycleClass c) const { return byClass_[static_cast<int>(c)] * layers_; }
  // Total cycles charged to `op` over all layers (0 if never charged) and its call count.
  double OpCycles(const std::string& op) const;
  int64_t OpCalls(const std::string& op) const;
  double ModelledSeconds() const { return TotalCycles() / profile_.clockHz; }

  // {"profile", "clockHz", "layers", "totalCycles", "modelledSeconds", "byClass": {...},
  //  "byLayer": [...], "byOp": {"add": {"calls", "cycles", "byClass", "microOps"}}}
  nlohmann::json Json() const;
  std::string Table() const;

 private:
  struct OpStats {
    int64_t calls = 0;
    MicroOpCounts counts;  // per layer
    MicroOpCounts whole;   // over all layers (ChargeWhole)
    std::array<double, kCycleClassCount> byClass{};
  };
  MachineProfile profile_;
  int layers_;
  std::array<double, kCycleClassCount> byClass_{};  // per layer
  std::map<std::string, OpStats> ops_;              // per layer
};

}  // namespace zephyr::bitserial
