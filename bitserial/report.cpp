#include "bitserial/report.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "fixed/check.h"

namespace zephyr::bitserial {

CycleReport::CycleReport(const MachineProfile* profile, int layers) : profile_(*profile) {
  runs_.push_back({.layers = layers});
}

CycleReport::ProgramRun& CycleReport::Single() {
  ZEPHYR_CHECK_EQ(runs_.size(), size_t(1));  // a sum of runs is read, not charged
  return runs_[0];
}
const CycleReport::ProgramRun& CycleReport::Single() const {
  ZEPHYR_CHECK_EQ(runs_.size(), size_t(1));
  return runs_[0];
}

void CycleReport::Charge(const std::string& op, const MicroOpCounts& counts) {
  ProgramRun& run = Single();
  auto cls = counts.ByClass(profile_);
  OpStats& s = run.ops[op];
  s.calls += 1;
  s.counts += counts;
  for (int i = 0; i < kCycleClassCount; ++i) {
    s.byClass[i] += cls[i];
    run.byClass[i] += cls[i];
  }
}

void CycleReport::ChargeWhole(const std::string& op, const MicroOpCounts& total) {
  ProgramRun& run = Single();
  auto cls = total.ByClass(profile_);
  OpStats& s = run.ops[op];
  s.calls += 1;
  s.whole += total;
  for (int i = 0; i < kCycleClassCount; ++i) {  // stored per layer, as every charge
    s.byClass[i] += cls[i] / run.layers;
    run.byClass[i] += cls[i] / run.layers;
  }
}

void CycleReport::Clear() {
  ProgramRun& run = Single();
  run.byClass = {};
  run.ops.clear();
}

bool CycleReport::SameCharges(const CycleReport& other) const {
  const ProgramRun &r = Single(), &o = other.Single();
  if (r.layers != o.layers || r.byClass != o.byClass || r.ops.size() != o.ops.size()) return false;
  for (auto a = r.ops.begin(), b = o.ops.begin(); a != r.ops.end(); ++a, ++b)
    if (a->first != b->first || a->second.calls != b->second.calls ||
        a->second.counts.n != b->second.counts.n || a->second.whole.n != b->second.whole.n ||
        a->second.byClass != b->second.byClass)
      return false;
  return true;
}

void CycleReport::Add(const CycleReport& other) {
  // A report of no run (a pass that ran no program: --method array on a view where no primary
  // ray hits, so no bounce runs) adds nothing, whatever profile it was made without.
  if (other.runs_.empty()) return;
  if (runs_.empty()) {
    *this = other;
    return;
  }
  ZEPHYR_CHECK(other.profile_.name == profile_.name && other.profile_.clockHz == profile_.clockHz);
  runs_.insert(runs_.end(), other.runs_.begin(), other.runs_.end());
}

CycleReport CycleReport::Run(int k) const {
  ZEPHYR_CHECK(k >= 0 && k < Runs());
  CycleReport r(&profile_, runs_[k].layers);
  r.runs_[0] = runs_[k];
  return r;
}

double CycleReport::ProgramRun::LayerCycles() const {
  double t = 0;
  for (double c : byClass) t += c;
  return t;
}

int CycleReport::Layers() const {
  int layers = 0;
  for (const ProgramRun& r : runs_) layers += r.layers;
  return layers;
}

double CycleReport::LayerCycles() const { return Single().LayerCycles(); }

// Every sum below is taken run by run in order (so a one-run report's figure is exactly that
// run's, and a sum's is the sum of its runs' reports as each prints them).
double CycleReport::TotalCycles() const {
  double t = 0;
  for (const ProgramRun& r : runs_) t += r.TotalCycles();
  return t;
}

double CycleReport::ClassCycles(CycleClass c) const {
  double t = 0;
  for (const ProgramRun& r : runs_) t += r.byClass[static_cast<int>(c)] * r.layers;
  return t;
}

double CycleReport::ModelledSeconds() const {
  double t = 0;
  for (const ProgramRun& r : runs_) t += r.TotalCycles() / profile_.clockHz;
  return t;
}

double CycleReport::OpCycles(const std::string& op) const {
  double total = 0;
  for (const ProgramRun& r : runs_) {
    auto it = r.ops.find(op);
    if (it == r.ops.end()) continue;
    double t = 0;
    for (double c : it->second.byClass) t += c;
    total += t * r.layers;
  }
  return total;
}

int64_t CycleReport::OpCalls(const std::string& op) const {
  int64_t calls = 0;
  for (const ProgramRun& r : runs_) {
    auto it = r.ops.find(op);
    if (it != r.ops.end()) calls += it->second.calls;
  }
  return calls;
}

// One path for one run and for a sum: each figure is summed run by run from 0, which for one
// run is exactly that run's figure.
nlohmann::json CycleReport::Json() const {
  using nlohmann::json;
  json j;
  j["profile"] = profile_.name;
  // A user's profile file is named by its path (a built-in one by its name alone).
  if (!profile_.file.empty() && profile_.file.rfind("built-in ", 0) != 0)
    j["profileFile"] = profile_.file;
  j["clockHz"] = profile_.clockHz;
  j["layers"] = Layers();
  j["totalCycles"] = TotalCycles();
  j["modelledSeconds"] = ModelledSeconds();
  json cls = json::object();
  for (int i = 0; i < kCycleClassCount; ++i)
    cls[CycleClassName(static_cast<CycleClass>(i))] = ClassCycles(static_cast<CycleClass>(i));
  j["byClass"] = cls;
  json byLayer = json::array();
  for (size_t k = 0; k < runs_.size(); ++k)
    for (int l = 0; l < runs_[k].layers; ++l) {
      if (runs_.size() == 1)
        byLayer.push_back({{"layer", l}, {"cycles", runs_[k].LayerCycles()}});
      else
        byLayer.push_back(
            {{"layer", byLayer.size()}, {"pass", k}, {"cycles", runs_[k].LayerCycles()}});
    }
  j["byLayer"] = byLayer;
  // Per op, over the runs that called it: calls, cycles, the classes and micro-ops it used.
  struct OpSum {
    int64_t calls = 0;
    double cycles = 0;
    std::map<int, double> byClass;
    std::map<int, int64_t> microOps;
  };
  std::map<std::string, OpSum> sums;
  for (const ProgramRun& r : runs_)
    for (const auto& [name, s] : r.ops) {
      OpSum& o = sums[name];
      o.calls += s.calls;
      double t = 0;
      for (int i = 0; i < kCycleClassCount; ++i) {
        t += s.byClass[i];
        if (s.byClass[i] != 0) o.byClass[i] += s.byClass[i] * r.layers;
      }
      o.cycles += t * r.layers;
      for (int i = 0; i < kMicroOpCount; ++i)
        if (s.counts.n[i] || s.whole.n[i]) o.microOps[i] += s.counts.n[i] * r.layers + s.whole.n[i];
    }
  json ops = json::object();
  for (const auto& [name, o] : sums) {
    json oc = json::object(), mo = json::object();
    for (const auto& [i, c] : o.byClass) oc[CycleClassName(static_cast<CycleClass>(i))] = c;
    for (const auto& [i, n] : o.microOps) mo[MicroOpName(static_cast<MicroOp>(i))] = n;
    ops[name] = {{"calls", o.calls}, {"cycles", o.cycles}, {"byClass", oc}, {"microOps", mo}};
  }
  j["byOp"] = ops;
  return j;
}

std::string CycleReport::Table() const {
  const ProgramRun& run = Single();
  const int layers = run.layers;
  std::string s = fmt::format(
      "cycle report — profile {}, {} virtual-PE layer{}, {:.0f} cycles = "
      "{:.6g} s at {:g} Hz\n",
      profile_.name, layers, layers == 1 ? "" : "s", TotalCycles(), ModelledSeconds(),
      profile_.clockHz);
  s += "  by class:\n";
  for (int i = 0; i < kCycleClassCount; ++i)
    s += fmt::format("    {:<16} {:>14.0f}\n", CycleClassName(static_cast<CycleClass>(i)),
                     run.byClass[i] * layers);
  s += fmt::format("  by layer: {} × {:.0f} cycles\n", layers, run.LayerCycles());
  s += fmt::format("  by operation:\n    {:<14} {:>8} {:>14} {:>12}\n", "op", "calls", "cycles",
                   "per call");
  for (auto& [name, st] : run.ops) {
    double t = 0;
    for (double c : st.byClass) t += c;
    s += fmt::format("    {:<14} {:>8} {:>14.0f} {:>12.1f}\n", name, st.calls, t * layers,
                     t * layers / st.calls);
  }
  return s;
}

}  // namespace zephyr::bitserial
