#include "bitserial/report.h"

#include <fmt/format.h>

namespace zephyr::bitserial {

void CycleReport::Charge(const std::string& op, const MicroOpCounts& counts) {
  auto cls = counts.ByClass(profile_);
  OpStats& s = ops_[op];
  s.calls += 1;
  s.counts += counts;
  for (int i = 0; i < kCycleClassCount; ++i) {
    s.byClass[i] += cls[i];
    byClass_[i] += cls[i];
  }
}

void CycleReport::ChargeWhole(const std::string& op, const MicroOpCounts& total) {
  auto cls = total.ByClass(profile_);
  OpStats& s = ops_[op];
  s.calls += 1;
  s.whole += total;
  for (int i = 0; i < kCycleClassCount; ++i) {  // stored per layer, as every charge
    s.byClass[i] += cls[i] / layers_;
    byClass_[i] += cls[i] / layers_;
  }
}

void CycleReport::Clear() {
  byClass_ = {};
  ops_.clear();
}

bool CycleReport::SameCharges(const CycleReport& o) const {
  if (layers_ != o.layers_ || byClass_ != o.byClass_ || ops_.size() != o.ops_.size()) return false;
  for (auto a = ops_.begin(), b = o.ops_.begin(); a != ops_.end(); ++a, ++b)
    if (a->first != b->first || a->second.calls != b->second.calls ||
        a->second.counts.n != b->second.counts.n || a->second.whole.n != b->second.whole.n ||
        a->second.byClass != b->second.byClass)
      return false;
  return true;
}

double CycleReport::LayerCycles() const {
  double t = 0;
  for (double c : byClass_) t += c;
  return t;
}

double CycleReport::OpCycles(const std::string& op) const {
  auto it = ops_.find(op);
  if (it == ops_.end()) return 0;
  double t = 0;
  for (double c : it->second.byClass) t += c;
  return t * layers_;
}

int64_t CycleReport::OpCalls(const std::string& op) const {
  auto it = ops_.find(op);
  return it == ops_.end() ? 0 : it->second.calls;
}

nlohmann::json CycleReport::Json() const {
  using nlohmann::json;
  json j;
  j["profile"] = profile_.name;
  j["clockHz"] = profile_.clockHz;
  j["layers"] = layers_;
  j["totalCycles"] = TotalCycles();
  j["modelledSeconds"] = ModelledSeconds();
  json cls = json::object();
  for (int i = 0; i < kCycleClassCount; ++i)
    cls[CycleClassName(static_cast<CycleClass>(i))] = byClass_[i] * layers_;
  j["byClass"] = cls;
  json layers = json::array();
  for (int l = 0; l < layers_; ++l) layers.push_back({{"layer", l}, {"cycles", LayerCycles()}});
  j["byLayer"] = layers;
  json ops = json::object();
  for (auto& [name, s] : ops_) {
    json o;
    o["calls"] = s.calls;
    double t = 0;
    json oc = json::object();
    for (int i = 0; i < kCycleClassCount; ++i) {
      t += s.byClass[i];
      if (s.byClass[i] != 0) oc[CycleClassName(static_cast<CycleClass>(i))] = s.byClass[i] * layers_;
    }
    o["cycles"] = t * layers_;
    o["byClass"] = oc;
    json mo = json::object();
    for (int i = 0; i < kMicroOpCount; ++i)
      if (s.counts.n[i] || s.whole.n[i])
        mo[MicroOpName(static_cast<MicroOp>(i))] = s.counts.n[i] * layers_ + s.whole.n[i];
    o["microOps"] = mo;
    ops[name] = o;
  }
  j["byOp"] = ops;
  return j;
}

std::string CycleReport::Table() const {
  std::string s = fmt::format("cycle report — profile {}, {} virtual-PE layer{}, {:.0f} cycles = "
                              "{:.6g} s at {:g} Hz\n", profile_.name, layers_,
                              layers_ == 1 ? "" : "s", TotalCycles(), ModelledSeconds(),
                              profile_.clockHz);
  s += "  by class:\n";
  for (int i = 0; i < kCycleClassCount; ++i)
    s += fmt::format("    {:<16} {:>14.0f}\n", CycleClassName(static_cast<CycleClass>(i)),
                     byClass_[i] * layers_);
  s += fmt::format("  by layer: {} × {:.0f} cycles\n", layers_, LayerCycles());
  s += fmt::format("  by operation:\n    {:<14} {:>8} {:>14} {:>12}\n", "op", "calls", "cycles",
                   "per call");
  for (auto& [name, st] : ops_) {
    double t = 0;
    for (double c : st.byClass) t += c;
    s += fmt::format("    {:<14} {:>8} {:>14.0f} {:>12.1f}\n", name, st.calls, t * layers_,
                     t * layers_ / st.calls);
  }
  return s;
}

}  // namespace zephyr::bitserial
