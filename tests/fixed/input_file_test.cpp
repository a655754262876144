// Every file a user hands the program is read one way (fixed/input_file.h): only a regular
// file, checked before it is opened (a FIFO would block for ever, a directory read as empty),
// never larger than its bound, each refusal naming the path and what was expected.
#include "fixed/input_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "fixed/check.h"
#include "tests/farm/mpi_launch.h"

namespace zephyr {
namespace {

constexpr InputKind kKind{"the test file", "a test file"};

std::string Error(const std::string& path, std::uintmax_t max = 1 << 20) {
  try {
    ReadInputFile(path, kKind, max);
  } catch (const UserError& e) {
    return e.what();
  }
  return "read";
}

TEST(InputFile, ARegularFileIsReadWhole) {
  testing::TempDir dir;
  const std::string file = dir / "a.txt";
  std::ofstream(file, std::ios::binary) << std::string("ab\0c", 4);
  EXPECT_EQ(ReadInputFile(file, kKind, 4), std::string("ab\0c", 4));
  EXPECT_EQ(CheckInputFile(file, kKind, 4), 4u);
}

TEST(InputFile, WhatIsNoRegularFileIsRefusedWithoutBlocking) {
  testing::TempDir dir;
  const std::string fifo = dir / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(Error(fifo), fifo + ": is not a regular file (a device, pipe or socket), expected a "
                                "test file");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));  // not opened
  EXPECT_EQ(Error("/dev/zero"),
            "/dev/zero: is not a regular file (a device, pipe or socket), expected a test file");
  const std::string folder = std::filesystem::path(fifo).parent_path().string();
  EXPECT_EQ(Error(folder), folder + ": is a directory, expected a test file");
  EXPECT_EQ(Error(dir / "none"), dir / "none" + ": cannot open the test file (no such file)");
  // A path through a regular file (ENOTDIR) names no file either: the same words, not the
  // system's "Not a directory".
  std::ofstream(dir / "plain") << "x";
  EXPECT_EQ(Error(dir / "plain" + "/scene.nff"),
            dir / "plain" + "/scene.nff: cannot open the test file (no such file)");
  EXPECT_EQ(Error(""), "an empty path names no file, expected a test file");
  // A name with a control byte is shown escaped, whole.
  EXPECT_EQ(Error(dir / "x\x01y"), dir / "x\\x01y" + ": cannot open the test file (no such file)");
}

TEST(InputFile, AFileLargerThanItsBoundIsRefusedBeforeItIsRead) {
  testing::TempDir dir;
  const std::string file = dir / "big";
  std::ofstream(file) << std::string(101, 'x');
  EXPECT_EQ(Error(file, 100), file + ": the test file has 101 bytes, more than the 100 bytes it may have");
  EXPECT_EQ(Error(file, 101), "read");
}

}  // namespace
}  // namespace zephyr
