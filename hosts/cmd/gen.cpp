// hosts/cmd/gen.cpp — `zephyr gen spheres|flake|showcase`: the generators of
// hosts/scene/gen.h, written as NFF to a file or standard output.
#include "hosts/scene/gen.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>

#include "fixed/check.h"
#include "hosts/cmd/command.h"
#include "hosts/cmd/flags.h"
#include "hosts/io/output_file.h"
#include "hosts/scene/nff.h"

namespace zephyr {
namespace {

void WriteSceneTo(const Scene& scene, const std::string& out) {
  const std::string text = WriteNff(scene);  // (--out was checked before the scene was made)
  if (out.empty() || out == "-") {
    std::fwrite(text.data(), 1, text.size(), stdout);
    return;
  }
  WriteOutputFile(out, "scene file", text);
}

void ParseSize(const std::string& size, int& w, int& h) {
  if (size.empty()) return;
  int a = 0, b = 0;
  char x = 0, extra = 0;
  if (std::sscanf(size.c_str(), "%d%c%d%c", &a, &x, &b, &extra) != 3 || (x != 'x' && x != 'X') ||
      a < 1 || b < 1 || a > 16384 || b > 16384)
    throw UserError("--size: expected WxH with 1..16384 on each side, got '" + size + "'");
  w = a;
  h = b;
}

CommandRegistration reg("gen", [](CLI::App& program) {
  auto* gen = program.add_subcommand("gen", "Generate a scene as NFF (deterministic from a seed)");
  gen->require_subcommand(1);
  struct Args {
    int count = 32, depth = 2;
    uint64_t seed = 1;
    std::string out, size;
  };
  auto args = std::make_shared<Args>();
  auto* spheres = gen->add_subcommand("spheres", "The paper's random-sphere scene");
  AddInteger(*spheres, "--count", args->count, 1, kMaxRandomSpheres, "Number of spheres")
      ->required();
  AddInteger(*spheres, "--seed", args->seed, uint64_t(0), UINT64_MAX, "Random seed")->required();
  spheres->add_option("--out", args->out, "Output file (default: standard output)");
  spheres->add_option("--size", args->size, "Image size WxH (default 384x384)");
  // Every generator checks --out before it generates (a flake of depth 6 takes a while).
  spheres->callback([args] {
    CheckOutputs({{"--out", args->out}});
    RandomSpheresOptions o;
    o.count = args->count;
    o.seed = args->seed;
    ParseSize(args->size, o.width, o.height);
    WriteSceneTo(GenerateRandomSpheres(o), args->out);
  });
  auto* flake = gen->add_subcommand("flake", "A sphereflake like SPD balls");
  AddInteger(*flake, "--depth", args->depth, 0, kMaxFlakeDepth,
             "Recursion depth (6 is 597,871 spheres)")
      ->required();
  flake->add_option("--out", args->out, "Output file (default: standard output)");
  flake->add_option("--size", args->size, "Image size WxH (default 512x512)");
  flake->callback([args] {
    CheckOutputs({{"--out", args->out}});
    int w = 512, h = 512;
    ParseSize(args->size, w, h);
    WriteSceneTo(GenerateSphereflake(args->depth, w, h), args->out);
  });
  auto* showcase =
      gen->add_subcommand("showcase", "Transformed primitives (ellipsoid, sheared cylinder, cube)");
  showcase->add_option("--out", args->out, "Output file (default: standard output)");
  showcase->add_option("--size", args->size, "Image size WxH (default 384x384)");
  showcase->callback([args] {
    CheckOutputs({{"--out", args->out}});
    int w = 384, h = 384;
    ParseSize(args->size, w, h);
    WriteSceneTo(GenerateTransformedShowcase(w, h), args->out);
  });
});

}  // namespace
}  // namespace zephyr
