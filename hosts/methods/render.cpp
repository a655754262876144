// hosts/methods/render.cpp — `zephyr render`: options, the method table, the outputs.
#include "hosts/methods/render.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <map>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/io/output_file.h"
#include "hosts/scene/nff.h"
#include "hosts/methods/phases.h"
#include "hosts/testbed/testbed.h"

namespace zephyr {

namespace {
struct MethodEntry {
  std::string description;
  RenderMethod run;
  RenderServeInstead serveInstead;
  RenderCheckOptions checkOptions;
};
std::map<std::string, MethodEntry>& Methods() {
  static std::map<std::string, MethodEntry> methods;
  return methods;
}
}  // namespace

RenderMethodRegistration::RenderMethodRegistration(std::string name, std::string description,
                                                   RenderMethod method,
                                                   RenderServeInstead serveInstead,
                                                   RenderCheckOptions checkOptions) {
  Methods().emplace(std::move(name),
                    MethodEntry{std::move(description), std::move(method), std::move(serveInstead),
                                std::move(checkOptions)});
}

namespace {
std::vector<std::function<void(CLI::App&, RenderOptions&)>>& FlagAdders() {
  static std::vector<std::function<void(CLI::App&, RenderOptions&)>> adders;
  return adders;
}
}  // namespace

RenderFlagRegistration::RenderFlagRegistration(
    std::function<void(CLI::App& command, RenderOptions& options)> add) {
  FlagAdders().push_back(std::move(add));
}

std::vector<std::string> RenderMethodNames() {
  std::vector<std::string> names;
  for (const auto& [name, entry] : Methods()) names.push_back(name);
  return names;
}

void WritePrimaryCsv(const std::string& path, int width, int height,
                     const std::vector<PrimarySample>& primary) {
  ZEPHYR_CHECK_EQ(primary.size(), size_t(width) * height);
  OutputFile file(path, "--dump-primary file");
  std::FILE* f = file.Stream();
  std::fprintf(f, "x,y,dx,dy,dz,object,t,flags\n");
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const PrimarySample& s = primary[size_t(y) * width + x];
      const Vec3& d = s.hit.direction;
      std::fprintf(f, "%d,%d,%.17g,%.17g,%.17g,%d,%.17g,%u\n", x, y, d.x, d.y, d.z, s.hit.object,
                   s.hit.object >= 0 ? s.hit.t : 0.0, s.flags);
    }
  }
  file.Commit();
}

void CheckRenderOutputs(const RenderOptions& options) {
  std::vector<std::pair<std::string, std::string>> outputs;  // flag, path
  for (const auto& [flag, path] : {std::pair{"--out", &options.out},
                                   std::pair{"--dump-primary", &options.dumpPrimary},
                                   std::pair{"--report", &options.report}})
    if (!path->empty()) outputs.emplace_back(flag, *path);
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const auto& [flag, path] = outputs[i];
    if (!options.scenePath.empty() && SameFile(path, options.scenePath))
      throw UserError(flag + " " + path + ": is the scene file being rendered; choose another name");
    for (std::size_t j = 0; j < i; ++j)
      if (SameFile(path, outputs[j].second))
        throw UserError(outputs[j].first + " and " + flag + " name the same file (" + path +
                        "); give each output its own name");
    CheckOutputPath(flag, path);
  }
}

RenderOutput RunRender(const RenderOptions& options) {
  auto it = Methods().find(options.method);
  if (it == Methods().end()) {
    std::string known;
    for (const auto& name : RenderMethodNames()) known += (known.empty() ? "" : ", ") + name;
    throw UserError("--method: unknown method '" + options.method + "' (known: " + known + ")");
  }
  RenderOutput out;
  if (it->second.serveInstead && it->second.serveInstead(options)) return out;
  // Every output and flag is checked before the scene is read: nothing is computed for an
  // output that could not be written.
  CheckRenderOutputs(options);
  if (it->second.checkOptions) it->second.checkOptions(options);
  out.report["method"] = options.method;
  Scene scene;
  {
    PhaseTimer timer(out.report, "read_scene");
    scene = ReadNffFile(options.scenePath);
  }
  for (const std::string& w : scene.warnings) std::fprintf(stderr, "zephyr: %s\n", w.c_str());
  const Camera& c = scene.camera;
  out.report["scene"] = {{"path", options.scenePath}, {"objects", scene.objects.size()},
                         {"lights", scene.lights.size()}, {"width", c.width}, {"height", c.height}};
  out.report["options"] = {{"depth", options.trace.depth},
                           {"precision", PrecisionName(options.trace.precision)},
                           {"sphere_test", SphereTestName(options.trace.sphereTest)}};
  {
    PhaseTimer timer(out.report, "render");
    it->second.run(scene, options, out);
  }
  testbed::AddModelledTime(options, scene, out);  // --testbed: modelled 1992 seconds
  ZEPHYR_CHECK(out.image.width == c.width && out.image.height == c.height);
  try {
    if (!options.out.empty()) {
      PhaseTimer timer(out.report, "write_png");
      WritePng(options.out, out.image);
    }
    if (!options.dumpPrimary.empty()) {
      if (out.primary.size() != size_t(c.width) * c.height)
        throw UserError("--dump-primary: method '" + options.method + "' does not produce primary hits");
      PhaseTimer timer(out.report, "dump_primary");
      WritePrimaryCsv(options.dumpPrimary, c.width, c.height, out.primary);
    }
    if (!options.report.empty())
      WriteOutputFile(options.report, "report", out.report.dump(2) + "\n");
  } catch (const UserError& e) {
    if (out.removeWhenWritten.empty()) throw;
    // The rendered frames are still on disk: say so, and how to finish without re-rendering.
    std::string kept;
    for (const std::string& path : out.removeWhenWritten) kept += (kept.empty() ? "" : ", ") + path;
    throw UserError(std::string(e.what()) + "; every rendered frame is kept in " + kept +
                    " — rerun with --resume to write the outputs without rendering them again");
  }
  // Only now, with every output on disk, is the checkpoint no longer needed.
  for (const std::string& path : out.removeWhenWritten) std::remove(path.c_str());
  return out;
}

// One line a user reads after a render: what was made, how long it took, where it went;
// for the distributed methods also frames and bytes (the JSON report has every figure).
std::string RenderSummary(const RenderOptions& options, const RenderOutput& out) {
  char line[512];
  const nlohmann::json& r = out.report;
  double seconds = r.contains("phases") && r["phases"].contains("render")
                       ? r["phases"]["render"].get<double>()
                       : 0.0;
  std::snprintf(line, sizeof line, "%s: %dx%d, %zu objects, rendered in %.3f s", options.method.c_str(),
                out.image.width, out.image.height, r["scene"]["objects"].get<size_t>(), seconds);
  std::string s = line;
  if (r.contains("distributed")) {
    const nlohmann::json& d = r["distributed"];
    const nlohmann::json& bytes = d["traffic"];
    auto total = [&](const char* way) {
      const nlohmann::json& t = bytes[way]["total"];
      return t["payloadBytes"].get<double>() + t["envelopeBytes"].get<double>();
    };
    std::snprintf(line, sizeof line,
                  "; %d children, %d frames sent, %d skipped, %.0f bytes to children, %.0f back",
                  d["children"].get<int>(), d["frames"]["sent"].get<int>(),
                  d["frames"]["skipped"].get<int>(), total("parentToChildren"),
                  total("childrenToParent"));
    s += line;
  }
  if (!options.out.empty()) s += "\n  image  " + options.out;
  if (!options.report.empty()) s += "\n  report " + options.report;
  if (!options.dumpPrimary.empty()) s += "\n  primary hits " + options.dumpPrimary;
  return s;
}

namespace {

CommandRegistration reg("render", [](CLI::App& program) {
  auto* cmd = program.add_subcommand("render", "Ray-trace a scene with one of the methods");
  auto o = std::make_shared<RenderOptions>();
  auto positional = std::make_shared<std::string>();
  auto precision = std::make_shared<std::string>("double");
  auto sphereTest = std::make_shared<std::string>("hb");
  auto noProgress = std::make_shared<bool>(false);
  std::string methods;
  for (const auto& name : RenderMethodNames()) methods += (methods.empty() ? "" : ", ") + name;
  cmd->add_option("--method", o->method, "Method: " + methods)->capture_default_str();
  cmd->add_option("--scene", o->scenePath, "NFF scene file");
  cmd->add_option("scene", *positional, "NFF scene file (same as --scene)");
  std::vector<CLI::Option*> outputs = {
      cmd->add_option("--out", o->out, "Output PNG"),
      cmd->add_option("--report", o->report, "JSON report: time per phase, rays, tests"),
      cmd->add_option("--dump-primary", o->dumpPrimary, "CSV of primary hits: x,y,dx,dy,dz,object,t,flags")};
  cmd->add_option("--depth", o->trace.depth, "Ray-tree depth limit (1 = primary rays only)")
      ->capture_default_str();
  cmd->add_option("--precision", *precision, "Host tracer scalar: float or double")->capture_default_str();
  cmd->add_option("--sphere-test", *sphereTest, "Sphere test form: hb (Hearn-Baker) or naive")
      ->capture_default_str();
  cmd->add_flag("--no-progress", *noProgress, "No progress bar even on a terminal");
  for (const auto& add : FlagAdders()) add(*cmd, *o);
  cmd->callback([o, positional, precision, sphereTest, noProgress, outputs] {
    RenderOptions options = *o;
    for (CLI::Option* flag : outputs)  // `--out ''` is a mistake, not "no output"
      if (flag->count() > 0 && flag->as<std::string>().empty())
        throw UserError(flag->get_name() + ": empty path (give a file name, or leave the flag out)");
    if (!positional->empty()) {
      if (!options.scenePath.empty() && options.scenePath != *positional)
        throw UserError("render: give the scene once (either --scene or a positional file)");
      options.scenePath = *positional;
    }
    if (options.scenePath.empty()) throw UserError("render: no scene (use --scene FILE)");
    options.trace.precision = ParsePrecision(*precision);
    options.trace.sphereTest = ParseSphereTest(*sphereTest);
    options.progress = !*noProgress && StderrIsTerminal();
    RenderOutput out = RunRender(options);
    if (!out.report.contains("method")) return;  // an MPI child: the parent reports
    std::printf("%s\n", RenderSummary(options, out).c_str());
  });
});

}  // namespace
}  // namespace zephyr
