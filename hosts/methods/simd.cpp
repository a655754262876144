// hosts/methods/simd.cpp — the SIMD/sequential method as a render method, its flags, and the
// `zephyr plan` command (the format planner's choice for a scene).
#include <CLI/CLI.hpp>
#include <cstdio>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/scene/nff.h"
#include "hosts/methods/render.h"
#include "hosts/methods/phases.h"
#include "hosts/simd/pass.h"

namespace zephyr::simd {

namespace {

// A width flag: unset = `fallback` (the planner chooses); else a whole number >= minimum.
int WidthFlag(const RenderOptions& o, const std::string& name, int fallback, int minimum,
              const char* unit) {
  auto it = o.extra.find(name);
  if (it == o.extra.end() || it->second.empty()) return fallback;
  int v = -1;
  try {
    size_t used = 0;
    v = std::stoi(it->second, &used);
    if (used != it->second.size()) v = -1;
  } catch (const std::exception&) {
    v = -1;
  }
  if (v < 0)
    throw UserError("--" + name + ": expected a whole number of bits, got '" + it->second + "'");
  if (v < minimum)
    throw UserError("--" + name + " " + it->second + ": the SIMD pass needs at least " +
                    std::to_string(minimum) + " " + unit +
                    " (the narrowest width its error bounds are tested at, docs/simd.md)");
  return v;
}

}  // namespace

SimdOptions SimdOptionsFrom(const RenderOptions& o) {
  SimdOptions s;
  s.formats.fracBits = WidthFlag(o, "frac-bits", -1, kMinFracBits, "fraction bits");
  s.formats.dirFracBits = WidthFlag(o, "dir-frac-bits", -1, kMinFracBits, "direction fraction bits");
  s.formats.intBits = WidthFlag(o, "int-bits", -1, kMinIntBits, "integer bits");
  if (auto it = o.extra.find("uncertain"); it != o.extra.end() && !it->second.empty())
    s.uncertain = ParseUncertainPolicy(it->second);
  if (auto it = o.extra.find("machine"); it != o.extra.end() && !it->second.empty())
    s.profile = it->second;
  return s;
}

namespace {

void RenderSimd(const Scene& scene, const RenderOptions& options, RenderOutput& out) {
  const Camera& c = scene.camera;
  PrimaryPass pass;
  {
    PhaseTimer timer(out.report, "primary_pass");
    pass = RunPrimaryPass(scene, SimdOptionsFrom(options));
  }
  std::fprintf(stderr, "cycle report (SIMD primary pass):\n%s", pass.cycleTable.c_str());
  std::fprintf(stderr, "uncertain pixels: %lld overflow, %lld grazing, %lld near tie; %lld recomputed on the host\n",
               (long long)pass.overflowPixels, (long long)pass.grazingPixels,
               (long long)pass.tiePixels, (long long)pass.recomputedPixels);
  if (pass.refinedPixels > 0)
    std::fprintf(stderr, "refine pass: %lld pixel(s) at %d fraction bits in %d layer(s), %.4g cycles; %lld still uncertain\n%s",
                 (long long)pass.refinedPixels, pass.refine["fracBits"].get<int>(), pass.refine["layers"].get<int>(),
                 pass.refine["cycles"]["totalCycles"].get<double>(), (long long)pass.refine["stillUncertain"].get<int64_t>(),
                 pass.refineCycleTable.c_str());
  const auto tracer = Tracer::Create(scene, options.trace);
  TraceStats stats;
  out.image = Image(c.width, c.height);
  {
    PhaseTimer timer(out.report, "host_shading");
    ShadeRegion(*tracer, pass.matrix, 0, 0, c.width, c.height, out.image.pixels, stats);
  }
  out.primary.clear();
  if (!options.dumpPrimary.empty())
    for (size_t i = 0; i < pass.matrix.hits.size(); ++i)
      out.primary.push_back({pass.matrix.hits[i], pass.matrix.flags[i]});
  out.report.update(stats.ToJson());
  out.report["simd"] = pass.Json();
}

RenderMethodRegistration reg("simd",
                             "SIMD/sequential: primary rays on the emulated array in fixed point, "
                             "secondary rays on the host",
                             RenderSimd, nullptr,
                             [](const RenderOptions& o) { SimdOptionsFrom(o); });

RenderFlagRegistration flags([](CLI::App& cmd, RenderOptions& o) {
  cmd.add_option("--frac-bits", o.extra["frac-bits"],
                 "simd: fraction bits of lengths, t and directions (default: planned per scene)");
  cmd.add_option("--dir-frac-bits", o.extra["dir-frac-bits"], "simd: fraction bits of the directions only");
  cmd.add_option("--int-bits", o.extra["int-bits"], "simd: integer bits of distances");
  cmd.add_option("--uncertain", o.extra["uncertain"],
                 "simd: uncertain pixels: recompute (default, in double on the host), refine (a second, "
                 "wider array pass on them first), keep, fail");
  cmd.add_option("--machine", o.extra["machine"], "simd: machine profile (wavetracer, mpp)");
});

CommandRegistration planCommand("plan", [](CLI::App& program) {
  auto* cmd = program.add_subcommand("plan", "Print the SIMD primary pass's formats for a scene, with reasons");
  auto scene = std::make_shared<std::string>();
  auto o = std::make_shared<RenderOptions>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("scene", *scene, "NFF scene file")->required();
  cmd->add_option("--frac-bits", o->extra["frac-bits"], "Fraction bits of lengths, t and directions");
  cmd->add_option("--dir-frac-bits", o->extra["dir-frac-bits"], "Fraction bits of the directions only");
  cmd->add_option("--int-bits", o->extra["int-bits"], "Integer bits of distances");
  cmd->add_option("--machine", o->extra["machine"], "Machine profile (wavetracer, mpp)");
  cmd->add_flag("--json", *json, "Machine-readable output");
  cmd->callback([scene, o, json] {
    const Scene s = ReadNffFile(*scene);
    const SimdOptions options = SimdOptionsFrom(*o);
    const PrimaryPlan plan = PlanPrimaryPass(s, options);
    // The cycle estimate: the pass's exact count on a one-layer machine, scaled by the layers.
    Scene small = s;
    small.camera.width = std::min(s.camera.width, 64);
    small.camera.height = std::min(s.camera.height, 64);
    SimdOptions keep = options;
    keep.uncertain = UncertainPolicy::kKeep;
    keep.formats = {plan.fracBits, plan.dirFracBits, plan.distIntBits};
    const PrimaryPass probe = RunPrimaryPass(small, keep);
    const double layerCycles = probe.cycles["totalCycles"].get<double>() / probe.plan.layers;
    const double cycles = layerCycles * plan.layers;
    const double clock = probe.cycles["clockHz"].get<double>();
    if (*json) {
      nlohmann::json j = plan.Json();
      j["objects"] = plan.ObjectsJson();
      j["cycleEstimate"] = cycles;
      j["modelledSecondsEstimate"] = cycles / clock;
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      std::printf("%s: %s", scene->c_str(), plan.Text().c_str());
      std::printf("cycle estimate: %.4g cycles per primary pass (%.4g per layer), %.4g s at %g MHz\n",
                  cycles, layerCycles, cycles / clock, clock / 1e6);
    }
  });
});

}  // namespace
}  // namespace zephyr::simd
