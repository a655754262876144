// `zephyr accuracy --method seq --precision float|double`: the sequential tracer's primary hits
// against the exact 128-bit reference, so float32 and float64 are points on the same
// speed-against-accuracy chart as the SIMD pass's fraction widths.
#include <gtest/gtest.h>

#include "tests/farm/mpi_launch.h"

namespace zephyr {
namespace {

using testing::RunZephyrProcess;
using testing::TempDir;

nlohmann::json Accuracy(const std::string& scene, const std::string& flags) {
  auto r = RunZephyrProcess("accuracy " + scene + " --json " + flags);
  EXPECT_EQ(r.status, 0) << r.output;
  return nlohmann::json::parse(r.output);
}

TEST(SeqAccuracy, DoubleFindsEveryFirstObjectAndFloatHasTheLargerTError) {
  TempDir dir;
  const std::string scene = dir / "s.nff";
  auto g = RunZephyrProcess("gen spheres --count 40 --seed 5 --size 64x48 --out " + scene);
  ASSERT_EQ(g.status, 0) << g.output;
  const auto d = Accuracy(scene, "--method seq --precision double");
  const auto f = Accuracy(scene, "--method seq --precision float");
  EXPECT_EQ(d["precision"], "double");
  EXPECT_EQ(f["precision"], "float");
  EXPECT_EQ(d["pixels"], 64 * 48);
  EXPECT_EQ(d["firstObjectDiffers"], 0);
  EXPECT_EQ(d["psnrDb"], "inf");      // seq double against itself
  EXPECT_TRUE(f.contains("psnrDb"));  // may be inf too: PSNR compares the 8-bit images
  EXPECT_GT(f["tMaxError"].get<double>(), d["tMaxError"].get<double>());
  EXPECT_GT(f["tMeanError"].get<double>(), 10 * d["tMeanError"].get<double>());
  EXPECT_LT(d["tMaxError"].get<double>(), 1e-9);  // double: rounding only
  EXPECT_GT(f["tMaxError"].get<double>(), 0);
}

TEST(SeqAccuracy, SimdFlagsWithSeqOrPrecisionWithSimdAreClearErrors) {
  TempDir dir;
  const std::string scene = dir / "s.nff";
  ASSERT_EQ(RunZephyrProcess("gen spheres --count 3 --seed 1 --size 8x8 --out " + scene).status, 0);
  auto a = RunZephyrProcess("accuracy " + scene + " --method seq --frac-bits 12");
  EXPECT_NE(a.status, 0);
  EXPECT_NE(a.output.find("--frac-bits applies to --method simd only"), std::string::npos)
      << a.output;
  auto b = RunZephyrProcess("accuracy " + scene + " --precision float");
  EXPECT_NE(b.status, 0);
  EXPECT_NE(b.output.find("--precision applies to --method seq"), std::string::npos) << b.output;
  auto c = RunZephyrProcess("accuracy " + scene + " --method dist");
  EXPECT_NE(c.status, 0);
  EXPECT_NE(c.output.find("expected simd or seq"), std::string::npos) << c.output;
}

}  // namespace
}  // namespace zephyr
