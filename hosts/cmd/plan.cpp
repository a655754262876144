// hosts/cmd/plan.cpp — `zephyr plan SCENE`: the SIMD primary pass's formats for a scene,
// with reasons, and a cycle estimate (docs/simd.md, "The planner").
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "hosts/cmd/command.h"
#include "hosts/cmd/simd_flags.h"
#include "hosts/scene/nff.h"
#include "hosts/simd/pass.h"

namespace zephyr {
namespace {

using namespace simd;

CommandRegistration planCommand("plan", [](CLI::App& program) {
  auto* cmd = program.add_subcommand(
      "plan", "Print the SIMD primary pass's formats for a scene, with reasons");
  auto scene = std::make_shared<std::string>();
  auto flags = std::make_shared<SimdFlags>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("scene", *scene, "NFF scene file")->required();
  flags->AddTo(*cmd, "", /*withUncertain=*/false);
  cmd->add_flag("--json", *json, "Machine-readable output");
  cmd->callback([scene, flags, json] {
    const Scene s = ReadNffFile(*scene);
    const SimdOptions options = flags->Options();
    const PrimaryPlan plan = PlanPrimaryPass(s, options);
    // The cycle estimate: the pass's exact count on a one-layer machine, scaled by the layers.
    Scene small = s;
    small.camera.width = std::min(s.camera.width, 64);
    small.camera.height = std::min(s.camera.height, 64);
    SimdOptions keep = options;
    keep.uncertain = UncertainPolicy::kKeep;
    keep.formats = {plan.fracBits, plan.dirFracBits, plan.distIntBits};
    if (plan.number == NumberSystem::kFloat) keep.floatFormat = plan.floatFormat;
    const PrimaryPass probe = RunPrimaryPass(small, keep);
    const double layerCycles = probe.array.cycles.TotalCycles() / probe.plan.layers;
    const double cycles = layerCycles * plan.layers;
    const double clock = probe.array.cycles.Profile().clockHz;
    if (*json) {
      nlohmann::json j = plan.Json();
      j["objects"] = plan.ObjectsJson();
      j["cycleEstimate"] = cycles;
      j["modelledSecondsEstimate"] = cycles / clock;
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      std::printf("%s: %s", scene->c_str(), plan.Text().c_str());
      std::printf(
          "cycle estimate: %.4g cycles per primary pass (%.4g per layer), %.4g s at %g MHz\n",
          cycles, layerCycles, cycles / clock, clock / 1e6);
    }
  });
});

}  // namespace
}  // namespace zephyr
