// hosts/cmd/mpi_check.cpp — `zephyr mpi-check`: the frame farm on its synthetic test pattern
// (hosts/farm/test_pattern.h), with no scene and no tracer — to check an MPI installation (a
// hostfile, a cluster) and to test the farm itself. `--local` computes the same image in one
// process without MPI, the reference the farm must reproduce bit for bit; the output is a PFM
// (portable float map) image.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/cmd/flags.h"
#include "hosts/farm/checkpoint.h"
#include "hosts/farm/farm.h"
#include "hosts/farm/test_pattern.h"
#include "hosts/io/output_file.h"
#include "hosts/methods/memory_budget.h"
#include "hosts/methods/render.h"
#include "hosts/scene/nff.h"

namespace zephyr {
namespace {

void WritePfm(const std::string& path, int width, int height, std::span<const std::byte> rgb) {
  std::string bytes = "PF\n" + std::to_string(width) + ' ' + std::to_string(height) +
                      "\n-1.0\n";  // little-endian, rows bottom-up
  const std::size_t row = std::size_t(width) * 12;
  for (int y = height - 1; y >= 0; --y)
    bytes.append(reinterpret_cast<const char*>(rgb.data() + y * row), row);
  WriteOutputFile(path, "PFM image", bytes);
}

void WriteJson(const std::string& path, const nlohmann::json& j) {
  if (path.empty()) return;
  WriteOutputFile(path, "report", j.dump(2) + '\n');
}

struct CheckArgs {
  PatternOptions pattern;
  int frame = 32;
  bool local = false;
  std::string out, report;
  FramedOptions farm;
};

void RunCheck(CheckArgs& a) {
  PatternOptions& o = a.pattern;
  if (o.mode != "dist" && o.mode != "hetero")
    throw UserError("--mode must be dist or hetero, got '" + o.mode + "'");
  if (!a.report.empty() &&
      (SameFile(a.report, a.out) || SameFile(a.report, CheckpointPathFor(a.out))))
    throw UserError("--report " + a.report +
                    ": is the image or its checkpoint; choose another name");
  if (LauncherRank() == 0) {  // children write no file and hold frames only
    CheckOutputs({{"--out", a.out}, {"--report", a.report}});
    // The parent's image (12 bytes a pixel), the farm's copy and, for hetero, the matrix (40).
    CheckMemoryFits("mpi-check at " + std::to_string(o.width) + "x" + std::to_string(o.height),
                    {.perPixel = 72, .pixels = uint64_t(o.width) * uint64_t(o.height)});
  }
  if (a.local) {
    WritePfm(a.out, o.width, o.height, RenderPatternLocally(o));
    return;
  }
  FrameGrid(o.width, o.height, a.frame);  // frame size 0 is an error before MPI starts
  auto factory = [](const std::string& setup) {
    return std::make_unique<PatternWork>(ParsePatternSetup(setup));
  };
  std::vector<PatternHit> matrix;  // hetero: the parent's, read by the job's slices
  a.farm.checkpointPath = CheckpointPathFor(a.out);
  if (ServeIfChild(o.mode, factory)) return;  // a child: served frames, no output
  const FramedResult result = RenderFrames(PatternJob(o, a.frame, matrix), a.farm);
  WritePfm(a.out, o.width, o.height, result.image);
  WriteJson(a.report, result.report.Json());
  RemoveCheckpoint(result.checkpointPath);  // only now: the outputs are on disk
}

CommandRegistration reg("mpi-check", [](CLI::App& program) {
  auto args = std::make_shared<CheckArgs>();
  auto* cmd = program.add_subcommand(
      "mpi-check",
      "Run the frame farm of dist/hetero on a synthetic pattern (check an MPI set-up; "
      "launch with mpirun -np K+1)");
  cmd->add_option("--mode", args->pattern.mode, "dist or hetero")->capture_default_str();
  AddInteger(*cmd, "--width", args->pattern.width, 1, kMaxResolution, "image width");
  AddInteger(*cmd, "--height", args->pattern.height, 1, kMaxResolution, "image height");
  AddInteger(*cmd, "--objects", args->pattern.objects, 0, 1000, "discs in the pattern");
  AddInteger(*cmd, "--work", args->pattern.work, 0, 100000000,
             "stand-in shading iterations per pixel");
  AddInteger(*cmd, "--seed", args->pattern.seed, std::uint32_t(0), UINT32_MAX, "pattern seed");
  AddInteger(*cmd, "--frame", args->frame, 1, kMaxResolution, "frame size F (F×F frames)");
  cmd->add_flag("--local", args->local, "render in this process, without MPI (the reference)");
  cmd->add_option("--out", args->out, "output image (.pfm)")->required();
  cmd->add_option("--report", args->report, "JSON report (parent)");
  cmd->add_flag("--resume", args->farm.resume,
                "render only the frames missing from the checkpoint");
  AddNumber(*cmd, "--child-timeout", args->farm.childTimeoutSeconds, kMinChildTimeoutSeconds,
            kNoUpperEnd, "seconds before a silent child holding frames is declared lost");
  AddInteger(*cmd, "--in-flight", args->farm.framesInFlight, 1, kMaxFramesInFlight,
             "frames handed to a child at once");
  cmd->callback([args] { RunCheck(*args); });
});

}  // namespace
}  // namespace zephyr
