// hosts/cmd/export_pov.cpp — `zephyr export-pov`: a scene as POV-Ray 3.7 SDL
// (hosts/scene/pov.h), with the povray command line that renders it.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/cmd/flags.h"
#include "hosts/io/output_file.h"
#include "hosts/scene/nff.h"
#include "hosts/scene/pov.h"
#include "hosts/trace/tracer.h"

namespace zephyr {
namespace {

CommandRegistration reg("export-pov", [](CLI::App& program) {
  auto* cmd = program.add_subcommand("export-pov",
                                     "Write a scene as POV-Ray 3.7 SDL (a reference renderer)");
  auto scene = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto depth = std::make_shared<int>(5);
  cmd->add_option("scene", *scene, "NFF scene file")->required();
  cmd->add_option("--out", *out, "Output .pov file (default: standard output)");
  AddInteger(*cmd, "--depth", *depth, 1, kMaxDepth, "Trace depth (POV-Ray max_trace_level)");
  cmd->callback([scene, out, depth] {
    CheckOutputs({{"--out", *out}}, {{"the scene file", *scene}});
    const Scene s = ReadNffFile(*scene);
    const std::string text = ExportPov(s, *depth);
    if (out->empty()) {
      std::fwrite(text.data(), 1, text.size(), stdout);
    } else {
      WriteOutputFile(*out, "POV-Ray file", text);
      std::fprintf(stderr, "render it with: %s\n",
                   PovrayCommand(*out, "out.png", s.camera.width, s.camera.height).c_str());
    }
  });
});

}  // namespace
}  // namespace zephyr
