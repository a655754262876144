// `zephyr render --method dist|hetero` under mpirun against seq and simd in one process: the
// same PNG bit for bit for frames of 1, 7, 32, 64 pixels and the whole image; hetero skips
// exactly the frames where no primary ray hit (read off simd's --dump-primary); a child
// killed mid-render loses no finished frame and --resume completes the same image.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "hosts/methods/hetero_entry.h"
#include "tests/farm/mpi_launch.h"

namespace zephyr {
namespace {

using testing::ReadFile;
using testing::ReadJson;
using testing::RunMpi;
using testing::RunZephyrProcess;
using testing::TempDir;

constexpr int kWidth = 40, kHeight = 30;

std::string Scene(const TempDir& dir) { return testing::SmallSphereScene(dir); }

std::string Single(const TempDir& dir, const std::string& scene, const std::string& method,
                   const std::string& extra = "") {
  std::string out = dir / (method + ".png");
  auto r = RunZephyrProcess("render --no-progress --method " + method + " " + scene + " --out " +
                            out + " " + extra);
  EXPECT_EQ(r.status, 0) << r.output;
  return out;
}

TEST(MpiRender, DistEqualsSeqAndHeteroEqualsSimdForEveryFrameSize) {
  TempDir dir;
  const std::string scene = Scene(dir);
  const std::string seq = ReadFile(Single(dir, scene, "seq"));
  const std::string simd = ReadFile(Single(dir, scene, "simd"));
  ASSERT_FALSE(seq.empty());
  for (const auto& [method, reference] : {std::pair{"dist", &seq}, std::pair{"hetero", &simd}})
    for (int frame : {1, 7, 32, 64, 40 /* the whole image */}) {
      std::string out = dir / (std::string(method) + std::to_string(frame) + ".png");
      auto r = RunMpi(3, "render --no-progress --method " + std::string(method) + " " + scene +
                             " --frame " + std::to_string(frame) + " --out " + out);
      ASSERT_EQ(r.status, 0) << r.output;
      EXPECT_EQ(ReadFile(out), *reference) << method << " with frames of " << frame;
    }
}

// On a cluster the scene file exists only where the parent runs: the children take the
// scene the parent sends. mpirun's MPMD form gives the children a path that does not exist.
TEST(MpiRender, ChildrenNeverReadTheSceneFile) {
  TempDir dir;
  const std::string scene = Scene(dir);
  const std::string seq = ReadFile(Single(dir, scene, "seq"));
  for (const char* method : {"dist", "hetero"}) {
    std::string out = dir / (std::string(method) + "-mpmd.png");
    std::string common = std::string("render --no-progress --method ") + method + " --frame 16 ";
    auto r = testing::RunCommand(
        "timeout -k 5 120 mpirun --oversubscribe --allow-run-as-root -np 1 " +
        testing::ZephyrPath() + " " + common + scene + " --out " + out + " : -np 2 " +
        testing::ZephyrPath() + " " + common + dir / "absent.nff" + " --out " + out);
    ASSERT_EQ(r.status, 0) << method << ": " << r.output;
    EXPECT_EQ(r.output.find("absent.nff"), std::string::npos) << r.output;
    if (std::string(method) == "dist") {
      EXPECT_EQ(ReadFile(out), seq);
    }
  }
}

// Two spheres in opposite corners of a 40×30 image: object 0 alone covers some 8×8 frames
// (object 0 is a hit like any other, never "no hit"), object 1 others, and the middle of the
// image is empty.
std::string CornerSpheresScene(const TempDir& dir) {
  std::string path = dir / "corners.nff";
  std::ofstream(path) << "v\nfrom 0 0 -10\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\n"
                         "resolution 40 30\nb 0.1 0.1 0.1\nl 0 10 -10\n"
                         "f 1 0 0 0.7 0.3 10 0 1\ns -2.6 1.6 0 0.9\n"
                         "f 0 0 1 0.7 0.3 10 0 1\ns 2.6 -1.6 0 0.9\n";
  return path;
}

// Frames whose primary rays hit nothing are skipped, exactly those, on the random spheres and
// on a scene where some frames' only hits are object 0.
void CheckHeteroSkips(const TempDir& dir, const std::string& scene, bool object0AloneInAFrame);

TEST(MpiRender, HeteroSkipsExactlyTheFramesWithNoPrimaryHit) {
  TempDir dir;
  CheckHeteroSkips(dir, Scene(dir), false);
}

TEST(MpiRender, HeteroShadesFramesWhoseOnlyHitIsObjectZero) {
  TempDir dir;
  CheckHeteroSkips(dir, CornerSpheresScene(dir), true);
  // and the image is simd's, object 0's frames included
  const std::string simd = ReadFile(Single(dir, dir / "corners.nff", "simd"));
  EXPECT_EQ(ReadFile(dir / "h.png"), simd);
}

void CheckHeteroSkips(const TempDir& dir, const std::string& scene, bool object0AloneInAFrame) {
  const std::string csv = dir / "primary.csv";
  Single(dir, scene, "simd", "--dump-primary " + csv);
  const int frame = 8, columns = 5, rows = 4;  // 40×30: the bottom row of frames is 6 high
  std::vector<bool> hit(columns * rows, false), other(columns * rows, false);
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // x,y,dx,dy,dz,object,t,flags
  int pixels = 0;
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::string field[8];
    for (auto& f : field) std::getline(s, f, ',');
    const int x = std::stoi(field[0]), y = std::stoi(field[1]), object = std::stoi(field[5]);
    if (object >= 0) hit[(y / frame) * columns + x / frame] = true;
    if (object > 0) other[(y / frame) * columns + x / frame] = true;
    ++pixels;
  }
  if (object0AloneInAFrame) {
    int alone = 0;
    for (int id = 0; id < columns * rows; ++id) alone += hit[id] && !other[id];
    ASSERT_GT(alone, 0) << "the scene should have frames hit by object 0 alone";
  }
  ASSERT_EQ(pixels, kWidth * kHeight);
  std::set<int> expected;
  for (int id = 0; id < columns * rows; ++id)
    if (!hit[id]) expected.insert(id);
  ASSERT_FALSE(expected.empty()) << "the scene should leave some frames empty";

  std::string report = dir / "h.json";
  auto r = RunMpi(3, "render --no-progress --method hetero " + scene + " --frame 8 --out " +
                         (dir / "h.png") + " --report " + report);
  ASSERT_EQ(r.status, 0) << r.output;
  auto j = ReadJson(report)["distributed"];
  EXPECT_EQ(j["frames"]["skippedIds"].get<std::set<int>>(), expected);
  EXPECT_EQ(j["frames"]["sent"], columns * rows - int(expected.size()));
  // Bytes: a work message is a 16-byte rectangle + a matrix entry per pixel, a result
  // the rectangle + 24 bytes (3 doubles) per pixel; the children counted the same.
  std::uint64_t sentPixels = 0;
  for (int id = 0; id < columns * rows; ++id)
    if (!expected.count(id)) sentPixels += 8 * (id / columns == rows - 1 ? 6 : 8);
  const std::uint64_t sent = columns * rows - expected.size();
  EXPECT_EQ(j["traffic"]["parentToChildren"]["work"]["payloadBytes"],
            16 * sent + hetero::kEntryBytes * sentPixels);
  EXPECT_EQ(j["traffic"]["childrenToParent"]["result"]["payloadBytes"],
            16 * sent + 24 * sentPixels);
  std::uint64_t childResultBytes = 0, childRays = 0;
  for (auto& c : j["perChild"]) {
    childResultBytes += c["sent"]["result"]["payloadBytes"].get<std::uint64_t>();
    childRays += c["work"]["rays"]["primary"].get<std::uint64_t>();
  }
  EXPECT_EQ(childResultBytes, 16 * sent + 24 * sentPixels);
  EXPECT_EQ(childRays, sentPixels);  // one primary ray shaded per pixel of a sent frame
  EXPECT_EQ(j["traffic"]["parentToChildren"]["work"]["messages"],
            columns * rows - int(expected.size()));
}

TEST(MpiRender, KillAChildThenResumeGivesTheCleanImage) {
  TempDir dir;
  const std::string scene = Scene(dir);
  const std::string args = "render --no-progress --method dist " + scene + " --frame 4 --out " +
                           (dir / "k.png") + " --report " + (dir / "k.json");
  auto resumed = testing::KillThenResume(args, dir / "k.png", 6);
  ASSERT_EQ(resumed.status, 0) << resumed.output;
  EXPECT_EQ(ReadFile(dir / "k.png"), ReadFile(Single(dir, scene, "seq")));
  auto j = ReadJson(dir / "k.json")["distributed"];
  EXPECT_EQ(j["frames"]["resumed"], 6);
  EXPECT_EQ(j["frames"]["sent"], 10 * 8 - 6);
}

TEST(MpiRender, DistWithoutMpirunOrWithFrameZeroIsAClearError) {
  TempDir dir;
  const std::string scene = Scene(dir);
  auto one = RunZephyrProcess("render --method dist " + scene + " --out " + (dir / "x.png"));
  EXPECT_NE(one.status, 0);
  EXPECT_NE(one.output.find("needs at least 2 MPI ranks"), std::string::npos) << one.output;
  auto zero =
      RunZephyrProcess("render --method hetero " + scene + " --frame 0 --out " + (dir / "x.png"));
  EXPECT_NE(zero.status, 0);
  EXPECT_NE(zero.output.find("--frame: expected an integer 1..16384, got '0'"), std::string::npos)
      << zero.output;
}

}  // namespace
}  // namespace zephyr
