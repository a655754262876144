// build/bin/example_life — Conway's Game of Life on the emulated Zephyr (docs/programming.md).
//
//   build/bin/example_life                          # 384x384 cells, 32 generations
//   build/bin/example_life --size 768 --generations 8 --profile mpp
//
// Runs the program of tools/examples/life.h on a machine with one virtual PE per cell,
// checks every generation against the plain C++ version, and prints the population and
// the cycle report. Exit 1 if the two ever differ, 2 on bad arguments.
//
// It includes only the installed API and its own header (by its own directory, so the two
// files build anywhere: docs/programming.md, "Building a program on the library").
#include "life.h"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <random>

#include "fixed/check.h"

int main(int argc, char** argv) {
  using namespace zephyr;
  CLI::App app("Conway's Game of Life as a MultiC-style program on the emulated Zephyr");
  int size = 384, generations = 32;
  uint64_t seed = 1;
  std::string profile = "wavetracer";
  app.add_option("--size", size, "Cells per side (a multiple of both physical mesh extents)")
      ->check(CLI::Range(1, 4096));
  app.add_option("--generations", generations, "Generations to run")->check(CLI::Range(0, 100000));
  app.add_option("--seed", seed, "Seed of the random first generation (one cell in three alive)");
  app.add_option("--machine,--profile", profile,
                 "Machine profile: a built-in name (wavetracer, mpp, blitzen) or a profile file");
  std::vector<std::string> overrides;
  app.add_option("--set", overrides, "Override a profile entry, NAME=VALUE (docs/bitserial.md)");
  CLI11_PARSE(app, argc, argv);
  try {
    bitserial::MachineProfile machine = bitserial::Profile(profile);
    for (const std::string& s : overrides) machine.Override(s);
    bitserial::Machine m(machine, int64_t{size} * size);
    const bitserial::MeshShape grid{{size, size}};
    bitserial::VirtualBlock(m, grid);  // refuse a size the mapping cannot place, up front
    std::mt19937_64 rng(seed);
    std::vector<int64_t> plain(m.VirtualPes());
    for (auto& c : plain) c = rng() % 3 == 0;
    bitserial::Multi alive(m, fixed::Format::Unsigned(1, 0), "alive");
    alive.LoadRaw(plain);
    m.Report().Clear();  // the report counts the generations only
    for (int g = 1; g <= generations; ++g) {
      alive = examples::LifeStep(alive, grid);
      plain = examples::LifeStepPlain(plain, size, size);
      for (int64_t pe = 0; pe < m.VirtualPes(); ++pe)  // a debugging read: not charged
        if (alive.BitAt(0, pe) != (plain[pe] != 0)) {
          fmt::print(stderr,
                     "generation {}: the array and the plain C++ version differ at "
                     "cell ({}, {})\n",
                     g, pe % size, pe / size);
          return 1;
        }
    }
    int64_t population = 0;
    for (int64_t c : plain) population += c;
    fmt::print(
        "{}x{} cells, {} generations on {} ({} virtual-PE layers): population {}, equal to "
        "the plain C++ version\n{:.0f} cycles per generation on the array\n",
        size, size, generations, profile, m.Layers(), population,
        generations ? m.Report().TotalCycles() / generations : 0.0);
    fmt::print("{}", m.Report().Table());
  } catch (const UserError& e) {
    fmt::print(stderr, "example_life: {}\n", e.what());
    return 2;
  }
  return 0;
}
