// build/bin/example_blur — a 3×3 box blur of a PNG on the emulated Zephyr
// (docs/programming.md).
//
//   build/bin/example_blur in.png out.png [--profile mpp]
//
// Every channel runs through the program of tools/examples/blur.h with one virtual PE per
// pixel (the image padded with 0 to whole blocks of the physical mesh), is checked against
// the plain C++ version and written to out.png; prints the cycles and the report. Exit 1 on
// any error (unreadable input, unwritable output, a difference).
#include "tools/examples/blur.h"

#include <fmt/format.h>

#include <CLI/CLI.hpp>

#include "fixed/check.h"
#include "hosts/cmd/command.h"

int main(int argc, char** argv) {
  using namespace zephyr;
  CLI::App app("A 3x3 box blur of a PNG as a MultiC-style program on the emulated Zephyr");
  std::string in, out, profile = "wavetracer";
  app.add_option("in", in, "Input PNG")->required();
  app.add_option("out", out, "Output PNG")->required();
  app.add_option("--machine,--profile", profile,
                 "Machine profile: a built-in name (wavetracer, mpp, blitzen) or a profile file");
  std::vector<std::string> overrides;
  app.add_option("--set", overrides, "Override a profile entry, NAME=VALUE (docs/bitserial.md)");
  RefuseEmptyValues(app);  // as every zephyr command: `example_blur '' out.png` is a mistake
  CLI11_PARSE(app, argc, argv);
  try {
    const examples::BlurResult r = examples::BlurPng(in, out, profile, overrides);
    fmt::print(
        "{}x{} pixels on a {}x{} virtual grid, {} ({} virtual-PE layers): equal to the "
        "plain C++ version; {:.0f} cycles per channel on the array; wrote {}\n",
        r.width, r.height, r.gridW, r.gridH, profile, r.layers, r.cyclesPerChannel, out);
    fmt::print("{}", r.reportTable);
  } catch (const UserError& e) {
    fmt::print(stderr, "example_blur: {}\n", e.what());
    return 1;
  }
  return 0;
}
