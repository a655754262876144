// --number float: the SIMD primary pass with the ray–sphere intersections in bit-serial float
// (hosts/simd/sphere_float.cpp, docs/simd.md "Floating point on the array"). Soundness
// against the exact (128-bit) reference at several formats — with `keep`, no pixel whose
// first object differs is unflagged; with `recompute`, none differs — agreement with the
// sequential tracer's first hits where certain, the float ops in the cycle report, and the
// refusal of objects it has no program for.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "fixed/check.h"
#include "hosts/scene/gen.h"
#include "hosts/scene/nff.h"
#include "hosts/simd/pass.h"
#include "hosts/trace/exact.h"
#include "tests/farm/mpi_launch.h"

namespace zephyr::simd {
namespace {

std::vector<exact::Hit> Exact(const Scene& scene) {
  const PrimaryRays rays(scene.camera);
  const std::vector<int> planes = exact::CoplanarPolygons(scene);
  std::vector<exact::Hit> out;
  for (int y = 0; y < scene.camera.height; ++y)
    for (int x = 0; x < scene.camera.width; ++x)
      out.push_back(
          exact::FirstHit(scene, rays.At(x, y), std::max(scene.camera.hither, 0.0), planes));
  return out;
}

SimdOptions FloatOptions(const std::string& format, UncertainPolicy policy) {
  SimdOptions o;
  o.number = NumberSystem::kFloat;
  if (!format.empty()) o.floatFormat = fixed::FloatFormat::Parse(format);
  o.uncertain = policy;
  return o;
}

// At each format ("" = planned): `keep` leaves no wrong pixel unflagged and certain t within
// the plan's bound; `recompute` leaves none wrong; a narrow format flags more than a wide one.
TEST(SimdFloat, SoundAgainstTheExactReferenceAtSeveralFormats) {
  const Scene scene = GenerateRandomSpheres({.count = 64, .seed = 1, .width = 48, .height = 48});
  const std::vector<exact::Hit> want = Exact(scene);
  int64_t narrowFlagged = -1;
  for (const std::string format : {"e5m7", "e5m10", "e6m12ftz", "e8m23", ""}) {
    const PrimaryPass kept = RunPrimaryPass(scene, FloatOptions(format, UncertainPolicy::kKeep));
    EXPECT_EQ(kept.plan.number, NumberSystem::kFloat);
    if (!format.empty()) {
      EXPECT_EQ(kept.plan.floatFormat.Name(), format);
    }
    int wrong = 0, unflaggedWrong = 0, flagged = 0, certainHits = 0;
    for (size_t i = 0; i < want.size(); ++i) {
      const PrimaryHit& h = kept.matrix.hits[i];
      flagged += kept.matrix.flags[i] != 0;
      if (h.object != want[i].object) ++wrong, unflaggedWrong += kept.matrix.flags[i] == 0;
      if (kept.matrix.flags[i] == 0 && h.object >= 0 && h.object == want[i].object) {
        ++certainHits;
        ASSERT_LE(std::abs(h.t - double(want[i].t)), kept.plan.tErrorBound)
            << format << " pixel " << i;
      }
    }
    EXPECT_EQ(unflaggedWrong, 0) << format << ": " << wrong << " wrong";
    if (format != "e5m7" && format != "e5m10") {
      EXPECT_GT(certainHits, 200) << format;  // the narrow two flag every hit of this scene
    }
    if (format == "e5m7") {
      narrowFlagged = flagged;
      EXPECT_GT(wrong, 0)
          << "e5m7 should get some first objects wrong (else the case proves little)";
    } else {
      EXPECT_LT(flagged, narrowFlagged) << format;
    }
    const PrimaryPass fixedUp =
        RunPrimaryPass(scene, FloatOptions(format, UncertainPolicy::kRecompute));
    int after = 0;
    for (size_t i = 0; i < want.size(); ++i)
      after += fixedUp.matrix.hits[i].object != want[i].object;
    EXPECT_EQ(after, 0) << format << " after recompute";
    EXPECT_EQ(fixedUp.recomputedPixels, flagged) << format;
  }
}

// Where the float pass is certain, its first object is the sequential (double) tracer's; the
// cycle report names the float operations as the fixed pass's names its own.
TEST(SimdFloat, CertainPixelsAgreeWithSeqAndTheReportShowsTheFloatOps) {
  const Scene scene = GenerateRandomSpheres({.count = 16, .seed = 4, .width = 40, .height = 40});
  const PrimaryPass pass = RunPrimaryPass(scene, FloatOptions("e8m16", UncertainPolicy::kKeep));
  const auto tracer = Tracer::Create(scene, TraceOptions{});
  const PrimaryRays rays(scene.camera);
  int certain = 0;
  for (int64_t i = 0; i < int64_t(pass.matrix.hits.size()); ++i) {
    if (pass.matrix.flags[i] != 0) continue;
    TraceStats stats;
    const PrimaryHit seq = tracer->FirstHit(rays.At(int(i % 40), int(i / 40)), stats);
    ASSERT_EQ(pass.matrix.hits[i].object, seq.object) << "pixel " << i;
    certain += seq.object >= 0;
  }
  EXPECT_GT(certain, 100);
  const nlohmann::json ops = pass.array.cycles.Json()["byOp"];
  for (const char* op : {"fmul", "fadd", "fsub", "fsqrt", "fmax", "fcompare", "ftofixed"}) {
    ASSERT_TRUE(ops.contains(op)) << op << " in " << ops.dump();
    EXPECT_GT(ops[op]["cycles"].get<double>(), 0) << op;
  }
  // Per sphere per layer: 12 multiplies, 3 adds + 2 in t, 4 subtractions + 1 in t.
  EXPECT_EQ(ops["fmul"]["calls"].get<int64_t>(), 12 * 16 * pass.plan.layers);
  EXPECT_EQ(pass.plan.Json()["number"], "float");
  EXPECT_EQ(pass.plan.Json()["floatFormat"], "e8m16");
  // The fixed pass of the same scene has no float op.
  const PrimaryPass fixedPass = RunPrimaryPass(scene, {});
  EXPECT_EQ(fixedPass.array.cycles.OpCalls("fmul"), 0);
}

TEST(SimdFloat, RefineRunsAWiderFloatAndStaysSound) {
  const Scene scene = GenerateRandomSpheres({.count = 32, .seed = 2, .width = 40, .height = 40});
  const std::vector<exact::Hit> want = Exact(scene);
  const PrimaryPass pass = RunPrimaryPass(scene, FloatOptions("e6m10", UncertainPolicy::kRefine));
  ASSERT_GT(pass.RefinedPixels(), 0);
  EXPECT_LT(pass.recomputedPixels, pass.RefinedPixels()) << "refine certified nothing";
  for (size_t i = 0; i < want.size(); ++i)
    ASSERT_EQ(pass.matrix.hits[i].object, want[i].object) << i;
}

// Objects without a float program are refused with their file:line, never run in fixed point
// or drawn wrong; a format whose range the scene's values exceed is refused too.
TEST(SimdFloat, OtherPrimitivesAndTooNarrowFormatsAreRefused) {
  const std::string head =
      "b 0 0 0\nv\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 30\nhither 0.01\nresolution 8 8\nl 5 5 "
      "5\n"
      "f 1 0.5 0.2 0.7 0.3 10 0 1\ns 0 0 0 1\n";
  const Scene cone = ParseNffOrThrow(head + "c 0 0 0 1 0 1 0 0.5\n", "cone.nff");
  try {
    RunPrimaryPass(cone, FloatOptions("", UncertainPolicy::kRecompute));
    FAIL() << "a cone ran in float";
  } catch (const UserError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("cone.nff:12"), std::string::npos) << what;
    EXPECT_NE(what.find("the float number system supports spheres only; this object is a cone"),
              std::string::npos)
        << what;
  }
  const Scene polygon = ParseNffOrThrow(head + "p 3\n-1 -1 0\n1 -1 0\n0 1 0\n", "poly.nff");
  EXPECT_THROW(RunPrimaryPass(polygon, FloatOptions("", UncertainPolicy::kRecompute)), UserError);
  const Scene far = ParseNffOrThrow(
      "b 0 0 0\nv\nfrom 0 0 3000\nat 0 0 0\nup 0 1 0\nangle 30\nhither 0.01\nresolution 8 8\nl 5 5 "
      "5\n"
      "f 1 0.5 0.2 0.7 0.3 10 0 1\ns 0 0 0 300\n",
      "far.nff");
  try {
    RunPrimaryPass(far, FloatOptions("e4m10", UncertainPolicy::kRecompute));
    FAIL() << "e4m10 ran a sphere 3000 away";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("beyond the float format e4m10"), std::string::npos)
        << e.what();
  }
}

TEST(SimdFloat, CommandLineFlags) {
  using zephyr::testing::RunZephyrProcess;
  using zephyr::testing::TempDir;
  TempDir dir;
  const std::string scene = dir / "s.nff", cone = dir / "c.nff";
  ASSERT_EQ(RunZephyrProcess("gen spheres --count 4 --seed 1 --size 16x16 --out " + scene).status,
            0);
  auto ok = RunZephyrProcess("accuracy " + scene + " --json --number float --float-format e8m20");
  ASSERT_EQ(ok.status, 0) << ok.output;
  EXPECT_EQ(nlohmann::json::parse(ok.output)["firstObjectDiffers"], 0);
  auto bad = RunZephyrProcess("accuracy " + scene + " --float-format e8m20");
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.output.find("applies to --number float only"), std::string::npos) << bad.output;
  // A cone is refused through the command line too: its file:line, a non-zero exit, no image.
  {
    std::FILE* f = std::fopen(cone.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs(
        "b 0 0 0\nv\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 30\nhither 0.01\nresolution 8 8\n"
        "l 5 5 5\nf 1 0.5 0.2 0.7 0.3 10 0 1\ns 0 0 0 1\nc 0 0 0 1 0 1 0 0.5\n",
        f);
    std::fclose(f);
  }
  const std::string png = dir / "cone.png";
  auto refused =
      RunZephyrProcess("render --method simd --scene " + cone + " --number float --out " + png);
  EXPECT_NE(refused.status, 0);
  EXPECT_NE(refused.output.find("c.nff:12"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("supports spheres only; this object is a cone"), std::string::npos)
      << refused.output;
  EXPECT_FALSE(std::filesystem::exists(png));
  // `zephyr plan` names the float format where the sphere's fixed formats were.
  auto plan = RunZephyrProcess("plan " + scene + " --number float --float-format e6m12");
  ASSERT_EQ(plan.status, 0) << plan.output;
  EXPECT_NE(plan.output.find("e6m12"), std::string::npos) << plan.output;
  EXPECT_EQ(plan.output.find("cross, clamped"), std::string::npos) << plan.output;
  auto word = RunZephyrProcess("render " + scene + " --method simd --number double --out " +
                               (dir / "x.png"));
  EXPECT_NE(word.status, 0);
  EXPECT_NE(word.output.find("--number: expected fixed or float"), std::string::npos)
      << word.output;
}

}  // namespace
}  // namespace zephyr::simd
