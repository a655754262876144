// hosts/cmd/render.cpp — `zephyr render`: the typed options of every method from the command
// line (the SIMD flags shared with plan and accuracy: hosts/cmd/simd_flags.h), then
// RunRender (hosts/methods/render.h), then what a user reads from its typed results: the
// array's tables (the primary pass's cycle report, its uncertain pixels and refine pass, the
// wavefront's bounces) and a one-line summary. The methods themselves print nothing.
#include "hosts/methods/render.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <vector>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/cmd/flags.h"
#include "hosts/cmd/simd_flags.h"
#include "hosts/methods/phases.h"
#include "hosts/scene/nff.h"
#include "hosts/testbed/testbed.h"

namespace zephyr {
// One line a user reads after a render: what was made, how long it took, where it went;
// for the distributed methods also frames and bytes (the JSON report has every figure).
namespace {

// The array's tables of a render, from its typed results: the primary pass's cycle report
// (simd, array, hetero), the uncertain pixels and the refine pass (simd), the bounces
// (array). "" for a method that ran nothing on the array.
std::string ArrayTables(const RenderOutput& out) {
  std::string s;
  if (!out.simd) return s;
  const simd::PrimaryPass& pass = *out.simd;
  s += "cycle report (SIMD primary pass):\n" + pass.array.Table();
  if (out.method == "simd") {
    s += fmt::format(
        "uncertain pixels: {} overflow, {} grazing, {} near tie; {} recomputed on the host\n",
        pass.uncertain.overflow, pass.uncertain.grazing, pass.uncertain.nearTie,
        pass.recomputedPixels);
    if (pass.refine)
      s += fmt::format("refine pass: {} pixel(s) at {} fraction bits in {} layer(s), {:.4g} cycles; "
                       "{} still uncertain\n",
                       pass.refine->pixels, pass.refine->fracBits, pass.refine->layers,
                       pass.refine->array.cycles.TotalCycles(), pass.refine->stillUncertain) +
           pass.refine->array.Table();
  }
  if (const auto& wave = out.wavefront) {
    s += fmt::format(
        "wavefront (compaction {}; s{}.{}, t error <= {:.3g}, rays ignore hits within {:.3g}):\n"
        "  bounce      rays      hits  layers passes  utilisation  uncertain rays/shadows  "
        "cycles\n",
        wavefront::kCompactionNames.NameOf(wave->compaction), wave->intBits, wave->fracBits,
        wave->tErrorBound, wave->epsilon);
    for (const wavefront::BounceReport& b : wave->bounces)
      s += fmt::format("  {:6} {:9} {:9} {:7} {:6} {:11.1f}% {:12} / {:<9} {:.4g}\n", b.bounce,
                       b.rays, b.hits, b.layers, b.passes, 100 * b.utilisation, b.uncertainRays,
                       b.uncertainShadows, b.cycles.TotalCycles());
    s += fmt::format("  total: {:.4g} cycles = {:.4g} s at {:.3g} Hz (primary pass {:.4g} s)\n",
                     wave->cycles.TotalCycles(), wave->cycles.ModelledSeconds(),
                     wave->cycles.Profile().clockHz, pass.array.ModelledSeconds());
  }
  return s;
}

std::string RenderSummary(const RenderOptions& options, const RenderOutput& out) {
  char line[512];
  const auto render = out.phases.find("render");
  const double seconds = render != out.phases.end() ? render->second : 0.0;
  std::snprintf(line, sizeof line, "%s: %dx%d, %zu objects, rendered in %.3f s",
                options.method.c_str(), out.image.width, out.image.height, out.scene.objects,
                seconds);
  std::string s = line;
  if (out.farm) {
    const FarmReport& d = *out.farm;
    auto total = [](const TrafficAccount& t) {
      const TrafficCount c = t.Total();
      return double(c.payloadBytes) + double(c.envelopeBytes);
    };
    std::snprintf(line, sizeof line,
                  "; %d children, %d frames sent, %zu skipped, %.0f bytes to children, %.0f back",
                  d.children, d.framesSent, d.skippedFrames.size(), total(d.parentToChildren),
                  total(d.childrenToParent));
    s += line;
  }
  if (out.testbed && out.testbed->ArrayActiveShare()) {
    std::snprintf(line, sizeof line, "\n  testbed %s: %.4g modelled s, array active %.1f %%",
                  out.testbed->testbed.c_str(), out.testbed->modelledSeconds,
                  100 * *out.testbed->ArrayActiveShare());
    s += line;
  }
  if (!options.out.empty()) s += "\n  image  " + options.out;
  if (!options.report.empty()) s += "\n  report " + options.report;
  if (!options.dumpPrimary.empty()) s += "\n  primary hits " + options.dumpPrimary;
  return s;
}

CommandRegistration reg("render", [](CLI::App& program) {
  auto* cmd = program.add_subcommand("render", "Ray-trace a scene with one of the methods");
  auto o = std::make_shared<RenderOptions>();
  auto positional = std::make_shared<std::string>();
  auto noProgress = std::make_shared<bool>(false);
  std::string methods;
  for (const auto& name : RenderMethodNames()) methods += (methods.empty() ? "" : ", ") + name;
  cmd->add_option("--method", o->method, "Method: " + methods)->capture_default_str();
  cmd->add_option("--scene", o->scenePath, "NFF scene file");
  cmd->add_option("scene", *positional, "NFF scene file (same as --scene)");
  cmd->add_option("--out", o->out, "Output PNG");
  cmd->add_option("--report", o->report, "JSON report: time per phase, rays, tests");
  cmd->add_option("--dump-primary", o->dumpPrimary,
                  "CSV of primary hits: x,y,dx,dy,dz,object,t,flags");
  AddInteger(*cmd, "--depth", o->trace.depth, 1, kMaxDepth,
             "Ray-tree depth limit (1 = primary rays only)");
  AddNamed(*cmd, "--precision", o->trace.precision, kPrecisionNames,
           "Host tracer scalar: float or double");
  AddNamed(*cmd, "--sphere-test", o->trace.sphereTest, kSphereTestNames,
           "Sphere test form: hb (Hearn-Baker) or naive");
  AddNamed(*cmd, "--accel", o->trace.accel, kAccelNames,
           "Host tracer: none (every object, the paper's) or bvh (a hierarchy; the same image)");
  cmd->add_flag("--no-progress", *noProgress, "No progress bar even on a terminal");
  auto simdFlags = std::make_shared<SimdFlags>();
  simdFlags->AddTo(*cmd, "simd: ");
  const std::vector<CLI::Option*> farmFlags = {
      AddInteger(*cmd, "--frame", o->dist.frameSize, 1, kMaxResolution,
                 "dist/hetero: frame size F (F×F frames)"),
      cmd->add_flag("--resume", o->dist.resume,
                    "dist/hetero: render only the frames missing from OUT.frames (the checkpoint)"),
      AddNumber(*cmd, "--child-timeout", o->dist.childTimeoutSeconds, kMinChildTimeoutSeconds,
                kNoUpperEnd, "dist/hetero: seconds a child may hold frames without answering"),
      AddInteger(*cmd, "--in-flight", o->dist.framesInFlight, 1, kMaxFramesInFlight,
                 "dist/hetero: frames handed to a child before it returns one")};
  const std::vector<CLI::Option*> wavefrontFlags = {
      AddNamed(*cmd, "--compact", o->wavefront.compaction, wavefront::kCompactionNames,
               "array: between bounces, none (every layer runs), local (each PE packs its live "
               "rays into its lowest layers) or mesh (local, then the PEs' counts evened over "
               "the mesh)"),
      AddInteger(*cmd, "--array-frac-bits", o->wavefront.fracBits, 8, 40,
                 "array: fraction bits of the secondary rays' numbers (default: the primary "
                 "plan's, at least 16)")};
  std::string testbeds;
  for (const auto& name : testbed::TestbedNames())
    testbeds += (testbeds.empty() ? "" : ", ") + name;
  cmd->add_option("--testbed", o->testbed,
                  "Model a whole system (" + testbeds +
                      "): the report's \"testbed\" gives modelled seconds (dist/hetero: under "
                      "tools/testbed/simrun.sh; it runs the testbed's array; docs/testbed.md)");
  cmd->add_option("--also-testbed", o->alsoTestbeds,
                  "seq, simd, array: also price the same counted work on this testbed (repeat "
                  "for more; each must share the array): the report's \"alsoTestbeds\"")
      ->allow_extra_args(false);  // one name a flag: a scene given after it is the scene
  cmd->callback([o, positional, noProgress, simdFlags, farmFlags, wavefrontFlags] {
    RenderOptions options = *o;
    if (!positional->empty()) {
      if (!options.scenePath.empty() && options.scenePath != *positional)
        throw UserError("render: give the scene once (either --scene or a positional file)");
      options.scenePath = *positional;
    }
    if (options.scenePath.empty()) throw UserError("render: no scene (use --scene FILE)");
    options.progress = !*noProgress && StderrIsTerminal();
    options.simd = simdFlags->Options();  // its value errors first
    // A flag the method would ignore is a mistake (as in `accuracy`), refused before any work
    // (after the values: a bad value is named as such whatever the method).
    const RenderMethodUse use = RenderMethodUses(options.method);
    if (!use.array && !simdFlags->Given().empty())
      throw UserError(simdFlags->Given().front() + ": --method " + options.method +
                      " runs no SIMD pass (the flag applies to " + RenderMethodsUsing(true, false) +
                      ")");
    for (const CLI::Option* flag : farmFlags)
      if (!use.farm && flag->count() > 0)
        throw UserError(flag->get_name() + ": --method " + options.method +
                        " has no frame farm (the flag applies to " +
                        RenderMethodsUsing(false, true) + ")");
    for (const CLI::Option* flag : wavefrontFlags)
      if (!use.wavefront && flag->count() > 0)
        throw UserError(flag->get_name() + ": --method " + options.method +
                        " traces no secondary ray on the array (the flag applies to array)");
    // On a named testbed the array is the testbed's unless --machine says otherwise (and then
    // it must be the same profile: testbed::CheckPricingRequest, in RunRender).
    const std::vector<std::string> simdGiven = simdFlags->Given();
    if (use.array && !options.testbed.empty() &&
        std::find(simdGiven.begin(), simdGiven.end(), "--machine") == simdGiven.end())
      if (const std::optional<std::string> array = testbed::TestbedArrayProfile(options.testbed)) {
        options.simd.profile = *array;
        simd::ResolveMachine(options.simd);
      }
    RenderOutput out = RunRender(options);
    std::printf("%s%s\n", ArrayTables(out).c_str(), RenderSummary(options, out).c_str());
  });
});

}  // namespace
}  // namespace zephyr
