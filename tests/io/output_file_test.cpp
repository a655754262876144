// Atomic output files (hosts/io/output_file.h): a committed file appears whole; an abandoned
// or failed one leaves the old file of that name untouched and no temporary behind — on a
// real full disk (a tiny tmpfs) too; output paths that cannot work are refused up front.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "fixed/check.h"
#include "hosts/io/output_file.h"
#include "hosts/trace/image.h"
#include "tests/farm/mpi_launch.h"

namespace zephyr {
namespace {

using testing::ReadFile;

int FilesIn(const std::string& dir) {
  int n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

TEST(OutputFile, AppearsOnlyWhenCommitted) {
  testing::TempDir dir;
  const std::string path = dir / "a.txt";
  std::ofstream(path) << "old";
  {
    OutputFile f(path, "text");
    std::fputs("new contents", f.Stream());
    EXPECT_EQ(ReadFile(path), "old") << "replaced before Commit";
    EXPECT_EQ(FilesIn(dir / ""), 2) << "the temporary sits beside the file";
  }  // abandoned, as when an exception unwinds
  EXPECT_EQ(ReadFile(path), "old");
  EXPECT_EQ(FilesIn(dir / ""), 1) << "temporary left behind";
  WriteOutputFile(path, "text", "new contents");
  EXPECT_EQ(ReadFile(path), "new contents");
  EXPECT_EQ(FilesIn(dir / ""), 1);
  EXPECT_EQ(std::filesystem::status(path).permissions() & std::filesystem::perms::others_read,
            std::filesystem::perms::others_read)
      << "mode as a plain create gives (0666 & ~umask), not mkstemp's 0600";
}

// A real full disk: the write fails at Commit with the system's reason, the good file of
// that name is intact and no temporary is left.
TEST(OutputFile, AFullDiskKeepsTheOldFileAndLeavesNoTemporary) {
  testing::TinyDisk disk(16 * 1024);
  if (!disk.Mounted()) GTEST_SKIP() << "needs root to mount a tmpfs";
  Image image(64, 64);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = {(i % 7) / 7.0, 0.5, 0.25};
  const std::string png = disk / "o.png";
  WritePng(png, image);
  const std::string good = ReadFile(png);
  ASSERT_FALSE(good.empty());
  testing::FillDisk(disk);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = {(i % 13) / 13.0, 1, 0};
  try {
    WritePng(png, image);
    FAIL() << "wrote a PNG on a full disk";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(png), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadFile(png), good) << "the old image was damaged";
  EXPECT_EQ(FilesIn(disk / ""), 2) << "o.png and the filler only";
  EXPECT_THROW(WriteOutputFile(disk / "r.json", "report", std::string(8192, 'x')), UserError);
  EXPECT_FALSE(std::filesystem::exists(disk / "r.json"));
  std::filesystem::remove(disk / "filler");
  WritePng(png, image);  // room again: the new image replaces the old
  EXPECT_NE(ReadFile(png), good);
  EXPECT_EQ(FilesIn(disk / ""), 1);
}

TEST(OutputFile, PathsThatCannotBeWrittenAreRefusedUpFront) {
  testing::TempDir dir;
  auto refused = [](const std::string& path, const std::string& why) {
    try {
      CheckOutputPath("--out", path);
      ADD_FAILURE() << path << " accepted";
    } catch (const UserError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).rfind("--out", 0), 0u) << e.what();
    }
  };
  refused("", "empty path");
  refused(dir / "", "is a directory");
  refused(dir / "missing/o.png", "does not exist");
  refused("/dev/full", "not a regular file");  // a rename would replace the device node
  std::ofstream(dir / "plain") << "x";
  refused(dir / "plain/o.png", "is not a directory");
  EXPECT_NO_THROW(CheckOutputPath("--out", dir / "o.png"));
  EXPECT_NO_THROW(CheckOutputPath("--out", dir / "plain"));  // an existing file is replaced
  EXPECT_EQ(FilesIn(dir / ""), 1) << "the probe file was left behind";
}

TEST(OutputFile, SameFileSeesThroughSpellingsAndLinks) {
  testing::TempDir dir;
  std::ofstream(dir / "s.nff") << "x";
  std::filesystem::create_directory(dir / "sub");
  std::filesystem::create_symlink(dir / "s.nff", dir / "link.nff");
  EXPECT_TRUE(SameFile(dir / "s.nff", dir / "sub/../s.nff"));
  EXPECT_TRUE(SameFile(dir / "s.nff", dir / "link.nff"));
  EXPECT_TRUE(SameFile(dir / "new.png", dir / "sub/../new.png"));  // neither exists yet
  EXPECT_FALSE(SameFile(dir / "s.nff", dir / "new.png"));
  EXPECT_FALSE(SameFile(dir / "a.png", dir / "b.png"));
}

}  // namespace
}  // namespace zephyr
