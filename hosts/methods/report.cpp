// hosts/methods/report.cpp — the render report, written once from the typed results.
#include "hosts/methods/report.h"

namespace zephyr {

namespace {

// One array pass's memory per virtual PE: peak and capacity, bits.
nlohmann::json MemoryJson(const simd::ArrayPassReport& pass) {
  return {{"internal",
           {{"peakBitsPerPe", pass.internalPeakBits},
            {"capacityBitsPerPe", pass.internalCapacityBits}}},
          {"external",
           {{"peakBitsPerPe", pass.externalPeakBits},
            {"capacityBitsPerPe", pass.externalCapacityBits}}}};
}

// One array pass's cycles: its cycle report, its memory per virtual PE, its timing.
nlohmann::json PassJson(const simd::ArrayPassReport& pass) {
  nlohmann::json j = pass.cycles.Json();
  j["memory"] = MemoryJson(pass);
  j["hostSeconds"] = pass.hostSeconds;
  j["realTimeFactor"] = pass.cycles.ModelledSeconds() / pass.hostSeconds;
  j["virtualPeRatio"] = pass.cycles.Layers();  // virtual PEs per physical PE: the layers
  return j;
}

}  // namespace

nlohmann::json ArrayRunJson(const simd::ArrayRunReport& run) {
  if (run.passes.size() == 1) return PassJson(run.passes[0]);
  nlohmann::json total = run.cycles.Json();
  total["memory"] = MemoryJson(run.passes.at(0));  // the first pass: the largest
  total["passes"] = nlohmann::json::array();
  for (size_t k = 0; k < run.passes.size(); ++k) {
    const simd::ArrayPassReport& p = run.passes[k];
    nlohmann::json entry = {
        {"pass", k}, {"firstPe", p.firstPe}, {"pes", p.pes}, {"cycles", PassJson(p)}};
    if (run.rowWidth > 0)
      entry["rows"] = {p.firstPe / run.rowWidth, (p.firstPe + p.pes) / run.rowWidth - 1};
    total["passes"].push_back(entry);
  }
  total["hostSeconds"] = run.hostSeconds;
  total["realTimeFactor"] = run.ModelledSeconds() / run.hostSeconds;
  return total;
}

nlohmann::json PrimaryPassJson(const simd::PrimaryPass& pass) {
  const double modelled = pass.array.ModelledSeconds(), host = pass.array.hostSeconds;
  nlohmann::json j = {{"plan", pass.plan.Json()},
                      {"cycles", ArrayRunJson(pass.array)},
                      {"hostSeconds", host},
                      {"modelledSeconds", modelled},
                      {"realTimeFactor", host > 0 ? modelled / host : 0.0},
                      {"recomputeSeconds", pass.recomputeSeconds},
                      {"uncertain",
                       {{"overflow", pass.uncertain.overflow},
                        {"grazing", pass.uncertain.grazing},
                        {"nearTie", pass.uncertain.nearTie},
                        {"recomputed", pass.recomputedPixels}}},
                      {"recomputeWork", pass.recomputeWork.ToJson()}};
  if (pass.refine) {
    const simd::RefineResult& r = *pass.refine;
    j["refine"] = {{"pixels", r.pixels},
                   {"layers", r.layers},
                   {"fracBits", r.fracBits},
                   {"dirFracBits", r.dirFracBits},
                   {"tErrorBound", r.tErrorBound},
                   {"stillUncertain", r.stillUncertain},
                   {"uncertain",
                    {{"overflow", r.uncertain.overflow},
                     {"grazing", r.uncertain.grazing},
                     {"nearTie", r.uncertain.nearTie}}},
                   {"hostSeconds", r.array.hostSeconds},
                   {"modelledSeconds", r.array.ModelledSeconds()},
                   {"cycles", ArrayRunJson(r.array)}};
  }
  return j;
}

namespace {

nlohmann::json WavefrontJson(const wavefront::WavefrontResult& w) {
  nlohmann::json rays;
  for (int k = 0; k < kRayKinds; ++k) rays[kRayKindNames[k]] = w.arrayRays[k];
  // Every bounce's cycles by class and operation (each bounce's own: "bounces"[].cycles).
  const nlohmann::json cycles = w.cycles.Json();
  nlohmann::json bounces = nlohmann::json::array();
  for (const wavefront::BounceReport& b : w.bounces)
    bounces.push_back({{"bounce", b.bounce},
                       {"rays", b.rays},
                       {"hits", b.hits},
                       {"layers", b.layers},
                       {"slots", b.slots},
                       {"passes", b.passes},
                       {"utilisation", b.utilisation},
                       {"uncertainRays", b.uncertainRays},
                       {"uncertainShadows", b.uncertainShadows},
                       {"spawned", b.spawned},
                       {"totalInternalReflections", b.totalInternalReflections},
                       {"hostLinkBytes", b.hostLinkBytes},
                       {"cycles", b.cycles.TotalCycles()},
                       {"compactionCycles", b.compactionCycles},
                       {"modelledSeconds", b.cycles.ModelledSeconds()},
                       {"hostSeconds", b.hostSeconds}});
  return {{"compaction", wavefront::kCompactionNames.NameOf(w.compaction)},
          {"format", {{"intBits", w.intBits}, {"fracBits", w.fracBits}}},
          {"tErrorBound", w.tErrorBound},
          {"epsilon", w.epsilon},
          {"arrayRays", rays},
          {"bounces", bounces},
          {"cycles", w.cycles.TotalCycles()},
          {"byClass", cycles["byClass"]},
          {"byOp", cycles["byOp"]},
          {"modelledSeconds", w.cycles.ModelledSeconds()}};
}

}  // namespace

nlohmann::json RenderReportJson(const RenderOutput& out) {
  nlohmann::json r = nlohmann::json::object();
  r["method"] = out.method;
  r["scene"] = {{"path", out.scene.path},
                {"objects", out.scene.objects},
                {"lights", out.scene.lights},
                {"width", out.scene.width},
                {"height", out.scene.height}};
  r["options"] = {{"depth", out.trace.depth},
                  {"precision", kPrecisionNames.NameOf(out.trace.precision)},
                  {"sphereTest", kSphereTestNames.NameOf(out.trace.sphereTest)},
                  {"accel", kAccelNames.NameOf(out.trace.accel)}};
  r["phases"] = out.phases;
  if (out.hostWork) r.update(out.hostWork->ToJson());  // the counters at the top level
  if (out.simd) r["simd"] = PrimaryPassJson(*out.simd);
  if (out.wavefront) r["wavefront"] = WavefrontJson(*out.wavefront);
  if (out.farm) r["distributed"] = out.farm->Json();
  if (out.testbed) r["testbed"] = out.testbed->Json();
  if (!out.alsoTestbeds.empty()) {
    r["alsoTestbeds"] = nlohmann::json::array();
    for (const testbed::ModelledTime& t : out.alsoTestbeds) r["alsoTestbeds"].push_back(t.Json());
  }
  return r;
}

}  // namespace zephyr
