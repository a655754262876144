// The kernel suite (tools/kernels/, docs/kernels.md): every kernel equals its plain C++
// version bit for bit on every built-in profile and every compiled Highway target, on one
// layer and on four (a grid whose blocks span layers on both axes), with the same cycles on
// every target; the largest size that fits a profile is the largest; build/bin/kernels
// refuses bad arguments with a message.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "tests/bitserial/testing.h"
#include "tools/kernels/suite.h"

namespace zephyr::kernels {
namespace {

TEST(ToolsKernels, EveryKernelEqualsPlainCppOnEveryProfileAndTarget) {
  // A profile without a 2-D mesh is left out of the suite, and its grid is refused clearly.
  const std::vector<std::string> grids = GridProfiles();
  for (const std::string& profile : bitserial::ProfileNames()) {
    const auto p = bitserial::Profile(profile);
    const bool grid = p.shapes.at(0).extent.size() == 2;
    EXPECT_EQ(grid, std::count(grids.begin(), grids.end(), profile) == 1);
    if (!grid) EXPECT_THROW(GridFor(p, p.physicalPes), UserError) << profile;
  }
  EXPECT_GE(grids.size(), 3u);  // wavetracer, mpp, blitzen
  for (const std::string& profile : grids) {
    const int pes = bitserial::Profile(profile).physicalPes;
    for (const auto& k : AllKernels())
      for (const int64_t elements : {int64_t{pes}, int64_t{4} * pes}) {
        std::optional<KernelRun> first;
        bitserial::testutil::ForEachTarget([&] {
          const KernelRun run = RunKernel(*k, profile, elements, {false, 3});
          EXPECT_EQ(run.difference, "")
              << k->Name() << " on " << profile << ", " << elements << " elements, " << run.target;
          EXPECT_EQ(run.layers, elements / pes);
          EXPECT_GT(run.report.TotalCycles(), 0);
          if (!first) first = run;
          EXPECT_TRUE(run.report.SameCharges(first->report))
              << k->Name() << " on " << profile << ": " << run.target
              << " charges other cycles than " << first->target;
        });
      }
  }
}

TEST(ToolsKernels, GridKernelsUseTheBlockedGrid) {
  const auto wt = bitserial::Profile("wavetracer"), mpp = bitserial::Profile("mpp");
  EXPECT_EQ(GridFor(wt, 8192).extent, (std::vector<int>{64, 128}));
  EXPECT_EQ(GridFor(wt, 2 * 8192).extent, (std::vector<int>{128, 128}));
  EXPECT_EQ(GridFor(wt, int64_t{1} << 20).extent, (std::vector<int>{1024, 1024}));
  EXPECT_EQ(GridFor(mpp, int64_t{1} << 20).extent, (std::vector<int>{1024, 1024}));
  EXPECT_THROW(GridFor(wt, 8192 * 3), UserError);  // three layers: not a power of two
  EXPECT_THROW(GridFor(wt, 4096), UserError);      // half a layer
}

// The MPP's 1024 bits per PE hold a 32-bit vector add (a, b and the sum: 96 bits per
// virtual PE) on 8 layers (128 bits each) but not on 16 (64 bits): the largest that fits is
// 8 layers, and the note says that 16 did not fit.
TEST(ToolsKernels, TheLargestSizeThatFitsIsTheLargest) {
  auto k = std::move(AllKernels().front());
  ASSERT_EQ(k->Name(), "vadd");
  const int pes = bitserial::Profile("mpp").physicalPes;
  const KernelRun run = RunLargestFitting(*k, "mpp", int64_t{64} * pes, {false, 1});
  EXPECT_EQ(run.layers, 8);
  EXPECT_EQ(run.difference, "");
  EXPECT_NE(run.note.find(std::to_string(16 * pes) + " elements do not fit"), std::string::npos)
      << run.note;
  try {
    RunKernel(*k, "mpp", int64_t{16} * pes, {false, 1});
    ADD_FAILURE() << "16 layers fit";
  } catch (const UserError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("PE memory full", 0), 0u) << e.what();
  }
  // Nothing smaller than one layer, nor a size that is not whole power-of-two layers.
  EXPECT_THROW(RunLargestFitting(*k, "mpp", pes / 2, {false, 1}), UserError);
  EXPECT_THROW(RunLargestFitting(*k, "mpp", int64_t{3} * pes, {false, 1}), UserError);
}

// build/bin/kernels: bad arguments get a message and exit 2; a small run prints its table.
TEST(ToolsKernels, TheProgramRefusesBadArgumentsAndRunsASmallCase) {
  const std::filesystem::path bin =
      std::filesystem::read_symlink("/proc/self/exe").parent_path() / "kernels";
  ASSERT_TRUE(std::filesystem::exists(bin)) << bin << " (built with the tests)";
  auto run = [&](const std::string& args, std::string* output) {
    FILE* pipe = ::popen(("'" + bin.string() + "' " + args + " 2>&1").c_str(), "r");
    char buffer[4096];
    output->clear();
    while (size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) output->append(buffer, n);
    const int status = ::pclose(pipe);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  std::string out;
  EXPECT_EQ(run("--profiles nosuch", &out), 2);
  EXPECT_NE(out.find("nosuch"), std::string::npos) << out;
  EXPECT_EQ(run("--kernels vadd,nosuch", &out), 2);
  EXPECT_NE(out.find("unknown kernel 'nosuch'"), std::string::npos) << out;
  EXPECT_EQ(run("--max-elements 12288 --profiles wavetracer", &out), 2);
  EXPECT_NE(out.find("power-of-two multiple"), std::string::npos) << out;
  EXPECT_EQ(run("--max-elements 0", &out), 2);
  // An empty list or item is named, never an empty table or "all" (issue 39).
  EXPECT_EQ(run("--profiles ,", &out), 2);
  EXPECT_NE(out.find("--profiles ',': an empty item"), std::string::npos) << out;
  EXPECT_EQ(run("--kernels vadd,,dot", &out), 2);
  EXPECT_NE(out.find("--kernels 'vadd,,dot': an empty item"), std::string::npos) << out;
  EXPECT_EQ(run("--kernels ''", &out), 2);
  EXPECT_NE(out.find("empty value"), std::string::npos) << out;
  EXPECT_EQ(run("--kernels dot --profiles mpp --max-elements 32768", &out), 0) << out;
  EXPECT_NE(out.find("dot product"), std::string::npos) << out;
  EXPECT_NE(out.find("mpp"), std::string::npos) << out;
}

}  // namespace
}  // namespace zephyr::kernels
