// Never lose finished work, and refuse bad outputs before any work starts
// (docs/distributed.md, "Durability"): outputs that overwrite the scene or each other, that
// cannot be created, or widths the SIMD pass cannot use are refused before the scene is
// traced (for hetero: before the SIMD pass); a full disk during a dist render, or a PNG
// write that fails after it, keeps every rendered frame in the checkpoint and --resume
// then writes the image bit for bit as a clean run; a damaged checkpoint costs only its bad
// records.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "tests/farm/mpi_launch.h"

namespace zephyr {
namespace {

using testing::ReadFile;
using testing::ReadJson;
using testing::RunMpi;
using testing::RunZephyrProcess;
using testing::TempDir;

std::string Scene(const TempDir& dir) { return testing::SmallSphereScene(dir); }

std::string SeqImage(const TempDir& dir, const std::string& scene) {
  auto r = RunZephyrProcess("render --no-progress --method seq " + scene + " --out " +
                            (dir / "seq.png"));
  EXPECT_EQ(r.status, 0) << r.output;
  return ReadFile(dir / "seq.png");
}

// `args` fails with a message containing `why`, before any work: the SIMD pass did not run
// (it prints its cycle report first) and no render summary was printed.
void ExpectRefusedUpFront(const testing::Launch& r, const std::string& why) {
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find(why), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("cycle report"), std::string::npos) << "work started: " << r.output;
  EXPECT_EQ(r.output.find("rendered in"), std::string::npos) << r.output;
}

TEST(RenderOutputs, OverwritingTheSceneOrAnotherOutputIsRefused) {
  TempDir dir;
  const std::string scene = Scene(dir);
  const std::string sceneText = ReadFile(scene);
  const std::string base = "render --no-progress --method simd " + scene;
  ExpectRefusedUpFront(RunZephyrProcess(base + " --out " + scene), "is the scene file");
  ExpectRefusedUpFront(
      RunZephyrProcess(base + " --out " + (dir / "x") + " --report " + (dir / "x")),
      "--out and --report name the same file");
  std::filesystem::create_directory(dir / "sub");
  ExpectRefusedUpFront(RunZephyrProcess(base + " --out " + (dir / "x.png") + " --dump-primary " +
                                        (dir / "sub/../x.png")),
                       "--out and --dump-primary name the same file");
  EXPECT_EQ(ReadFile(scene), sceneText) << "the scene was overwritten";
  for (const char* flag : {"--out", "--report", "--dump-primary"})
    ExpectRefusedUpFront(RunZephyrProcess(base + " " + flag + " ''"),
                         std::string(flag) + ": empty value");
  EXPECT_FALSE(std::filesystem::exists(dir / "x"));
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

TEST(RenderOutputs, PathsThatCannotBeWrittenAreRefusedBeforeTheRender) {
  TempDir dir;
  const std::string scene = Scene(dir);
  const std::string base =
      "render --no-progress --method simd " + scene + " --out " + (dir / "o.png");
  std::filesystem::create_directory(dir / "d");
  ExpectRefusedUpFront(RunZephyrProcess("render --method seq " + scene + " --out " + (dir / "d")),
                       "is a directory");
  ExpectRefusedUpFront(RunZephyrProcess(base + " --report " + (dir / "missing/r.json")),
                       "does not exist");
  ExpectRefusedUpFront(RunZephyrProcess(base + " --dump-primary /dev/full"), "not a regular file");
  EXPECT_FALSE(std::filesystem::exists(dir / "o.png")) << "an image was left behind";
}

TEST(RenderWidths, WidthsBelowWhatThePassNeedsAreRefusedWithTheMinimum) {
  TempDir dir;
  const std::string scene = Scene(dir);
  const std::string base =
      "render --no-progress --method simd " + scene + " --out " + (dir / "o.png");
  ExpectRefusedUpFront(RunZephyrProcess(base + " --frac-bits 0"),
                       "--frac-bits: expected an integer 4..56, got '0' (the SIMD pass's error "
                       "bounds are tested from 4 bits");
  ExpectRefusedUpFront(RunZephyrProcess(base + " --frac-bits 3"),
                       "--frac-bits: expected an integer 4..56, got '3'");
  ExpectRefusedUpFront(RunZephyrProcess(base + " --dir-frac-bits 0"),
                       "--dir-frac-bits: expected an integer 4..60, got '0'");
  ExpectRefusedUpFront(RunZephyrProcess(base + " --int-bits 0"),
                       "--int-bits: expected an integer 2..40, got '0'");
  ExpectRefusedUpFront(RunZephyrProcess("accuracy " + scene + " --int-bits 1"),
                       "--int-bits: expected an integer 2..40, got '1'");
  EXPECT_FALSE(std::filesystem::exists(dir / "o.png"));
  auto atMinimum = RunZephyrProcess(base + " --frac-bits 4 --int-bits 2");  // N and N-1
  EXPECT_EQ(atMinimum.status, 0) << atMinimum.output;
}

// dist and hetero check their own flags and the checkpoint OUT.frames on the parent before
// any frame (hetero: before the SIMD pass); hetero dumps the matrix as simd does.
TEST(RenderOutputs, DistAndHeteroCheckEverythingBeforeTheFirstFrame) {
  TempDir dir;
  const std::string scene = Scene(dir);
  const std::string out = dir / "o.png";
  const std::string hetero =
      "render --no-progress --method hetero --frame 16 " + scene + " --out " + out;
  ExpectRefusedUpFront(RunMpi(2, hetero + " --report " + out + ".frames"),
                       "is the checkpoint of --out");
  ExpectRefusedUpFront(RunMpi(2, hetero + " --frac-bits 0"),
                       "--frac-bits: expected an integer 4..56, got '0'");
  ExpectRefusedUpFront(RunMpi(2, hetero + " --resume"), "nothing to resume");
  ExpectRefusedUpFront(RunMpi(2, "render --method dist " + scene + " --out " + out +
                                     " --dump-primary " + (dir / "p.csv")),
                       "--method dist has no primary hits");
  EXPECT_FALSE(std::filesystem::exists(out));
  auto simd = RunZephyrProcess("render --no-progress --method simd " + scene + " --dump-primary " +
                               (dir / "simd.csv"));
  ASSERT_EQ(simd.status, 0) << simd.output;
  auto r = RunMpi(3, hetero + " --dump-primary " + (dir / "hetero.csv"));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(ReadFile(dir / "hetero.csv"), ReadFile(dir / "simd.csv"));
}

// 40×30 pixels in 16×16 frames: 6 frames, 1200 pixels of 24 bytes; a checkpoint of a
// 32-byte header and a 16 + 8 byte frame around each record: 28 976 bytes, 8 tmpfs pages.
// A disk of exactly those pages holds the whole checkpoint and not one byte of the PNG.
TEST(RenderDurability, AFailedPngWriteAfterADistRenderKeepsTheFramesAndResumeWritesTheSameImage) {
  TempDir dir;
  const std::string scene = Scene(dir);
  const std::string seq = SeqImage(dir, scene);
  testing::TinyDisk disk(8 * 4096);
  if (!disk.Mounted()) GTEST_SKIP() << "needs root to mount a tmpfs";
  const std::string out = disk / "o.png";
  const std::string args = "render --no-progress --method dist --frame 16 " + scene + " --out " +
                           out + " --report " + (dir / "r.json");
  auto full = RunMpi(3, args);
  EXPECT_NE(full.status, 0) << full.output;
  EXPECT_NE(full.output.find("No space left on device"), std::string::npos) << full.output;
  EXPECT_NE(full.output.find("--resume"), std::string::npos) << full.output;
  EXPECT_FALSE(std::filesystem::exists(out)) << "a partial PNG";
  ASSERT_TRUE(std::filesystem::exists(out + ".frames")) << full.output;
  EXPECT_EQ(std::filesystem::file_size(out + ".frames"), 32 + 6 * 24 + 1200 * 24u);
  ASSERT_TRUE(disk.Resize(1 << 20));
  auto resumed = RunMpi(3, args + " --resume");
  ASSERT_EQ(resumed.status, 0) << resumed.output;
  EXPECT_EQ(ReadFile(out), seq) << "not the clean run's image";
  EXPECT_FALSE(std::filesystem::exists(out + ".frames")) << "checkpoint kept after success";
  auto j = ReadJson(dir / "r.json")["distributed"]["frames"];
  EXPECT_EQ(j["resumed"], 6);
  EXPECT_EQ(j["sent"], 0) << "frames rendered again";
}

// The disk fills while frames arrive: the checkpoint write fails, the parent stops with the
// frames written so far kept; with room again --resume renders only the rest.
TEST(RenderDurability, AFullDiskDuringADistRenderKeepsEveryWrittenFrame) {
  TempDir dir;
  const std::string scene = Scene(dir);
  const std::string seq = SeqImage(dir, scene);
  testing::TinyDisk disk(4 * 4096);  // the checkpoint of 80 4×4 frames needs 8 pages
  if (!disk.Mounted()) GTEST_SKIP() << "needs root to mount a tmpfs";
  const std::string out = disk / "o.png";
  const std::string args = "render --no-progress --method dist --frame 4 " + scene + " --out " +
                           out + " --report " + (dir / "r.json");
  auto full = RunMpi(2, args);
  EXPECT_NE(full.status, 0) << full.output;
  EXPECT_NE(full.output.find("cannot write checkpoint"), std::string::npos) << full.output;
  EXPECT_NE(full.output.find("No space left on device"), std::string::npos) << full.output;
  EXPECT_NE(full.output.find("rerun with --resume"), std::string::npos) << full.output;
  EXPECT_FALSE(std::filesystem::exists(out));
  ASSERT_TRUE(std::filesystem::exists(out + ".frames"));
  ASSERT_TRUE(disk.Resize(1 << 20));
  auto resumed = RunMpi(3, args + " --resume");
  ASSERT_EQ(resumed.status, 0) << resumed.output;
  EXPECT_EQ(ReadFile(out), seq);
  auto j = ReadJson(dir / "r.json")["distributed"]["frames"];
  EXPECT_GE(j["resumed"].get<int>(), 30) << "16 KiB hold at least 30 records of 408 bytes";
  EXPECT_EQ(j["resumed"].get<int>() + j["sent"].get<int>(), 80);
}

// A child is killed after 6 frames; one bit of the second record is flipped: --resume keeps
// the 5 intact frames, names the bad one, renders it and the rest again, and the image is
// the clean run's.
TEST(RenderDurability, ADamagedCheckpointCostsOnlyItsBadRecord) {
  TempDir dir;
  const std::string scene = Scene(dir);
  const std::string out = dir / "k.png";
  const std::string args = "render --no-progress --method dist --frame 4 " + scene + " --out " +
                           out + " --report " + (dir / "k.json");
  auto killed = RunMpi(2, args, "-x ZEPHYR_TEST_FAULT=kill:1:6");
  ASSERT_NE(killed.status, 0) << killed.output;
  std::string bytes = ReadFile(out + ".frames");
  const std::size_t record = 16 + 16 * 24 + 8, second = 32 + record;
  ASSERT_GE(bytes.size(), 32 + 6 * record) << killed.output;
  std::uint32_t badFrame;
  std::memcpy(&badFrame, &bytes[second + 4], 4);
  bytes[second + 16 + 100] ^= 1;
  std::ofstream(out + ".frames", std::ios::binary) << bytes;
  auto resumed = RunMpi(3, args + " --resume");
  ASSERT_EQ(resumed.status, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("5 intact frames kept; 1 bad record(s) for frames " +
                                std::to_string(badFrame)),
            std::string::npos)
      << resumed.output;
  EXPECT_EQ(ReadFile(out), SeqImage(dir, scene));
  auto j = ReadJson(dir / "k.json")["distributed"]["frames"];
  EXPECT_EQ(j["resumed"], 5);
  EXPECT_EQ(j["checkpointDamaged"], nlohmann::json::array({badFrame}));
  EXPECT_EQ(j["sent"], 80 - 5);
}

}  // namespace
}  // namespace zephyr
