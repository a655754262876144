// Tests for `zephyr stability` (hosts/cmd/stability.cpp): the Ray Tracing Gems ch. 7
// failure of the naive sphere test, its fixed-point counterpart, and the overflow boundary.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "hosts/cmd/command.h"

namespace zephyr {
namespace {

using Row = std::map<std::string, std::string>;

std::vector<Row> ReadCsv(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::vector<std::string> header;
  std::vector<Row> rows;
  auto split = [](const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string cell; std::getline(ss, cell, ',');) out.push_back(cell);
    return out;
  };
  if (std::getline(f, line)) header = split(line);
  while (std::getline(f, line)) {
    const auto cells = split(line);
    Row row;
    for (size_t i = 0; i < header.size() && i < cells.size(); ++i) row[header[i]] = cells[i];
    rows.push_back(row);
  }
  return rows;
}

const Row& Find(const std::vector<Row>& rows, const std::string& distance, const std::string& form,
                const std::string& format) {
  for (const Row& r : rows)
    if (r.at("distance") == distance && r.at("form") == form && r.at("format") == format) return r;
  ADD_FAILURE() << "no row " << distance << " " << form << " " << format;
  static const Row kEmpty;
  return kEmpty;
}

std::string TempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("zephyr_stability_" + name)).string();
}

TEST(StabilityDistance, NaiveLosesTheRadiusFarAwayAndHearnBakerKeepsIt) {
  const std::string out = TempPath("distance.csv");
  const char* argv[] = {"zephyr",
                        "stability",
                        "distance",
                        "--out",
                        out.c_str(),
                        "--formats",
                        "float32,float64,s15.16",
                        "--rays",
                        "64",
                        "--max-log2",
                        "14",
                        "--steps",
                        "1"};
  ASSERT_EQ(RunZephyr(13, argv), 0);
  const auto rows = ReadCsv(out);
  ASSERT_EQ(rows.size(), 14u * 2 * 3);  // distances 2^1..2^14, two forms, three formats
  // Near: every form and format is right.
  for (const char* form : {"naive", "hb"})
    for (const char* format : {"float32", "float64", "s15.16"})
      EXPECT_EQ(std::stod(Find(rows, "4", form, format).at("wrong_hit_pct")), 0) << form << format;
  // Far (16384 r): float32 naive calls the rays past the radius hits (RTG ch. 7: the radius
  // stops mattering beyond ~4096 r); Hearn-Baker in float32 and the naive form in float64 stay
  // right.
  EXPECT_GT(std::stod(Find(rows, "16384", "naive", "float32").at("wrong_hit_pct")), 10);
  EXPECT_EQ(std::stod(Find(rows, "16384", "hb", "float32").at("wrong_hit_pct")), 0);
  EXPECT_EQ(std::stod(Find(rows, "16384", "naive", "float64").at("wrong_hit_pct")), 0);
  EXPECT_LT(std::stod(Find(rows, "16384", "hb", "float32").at("t_relerr_max")), 1e-6);
  // Fixed s15.16: the naive form squares the distance, so at 2^9 r it is flagged or wrong;
  // Hearn-Baker needs integer bits for the distance only and is still right.
  const Row& naive = Find(rows, "512", "naive", "s15.16");
  EXPECT_GT(std::stod(naive.at("wrong_hit_pct")) + std::stod(naive.at("flagged_pct")), 10);
  EXPECT_EQ(std::stod(Find(rows, "512", "hb", "s15.16").at("wrong_hit_pct")), 0);
  EXPECT_EQ(std::stod(Find(rows, "512", "hb", "s15.16").at("flagged_pct")), 0);
  std::filesystem::remove(out);
}

TEST(StabilityOverflow, HearnBakerHoldsTheSquareOfTheNaiveExtent) {
  const std::string out = TempPath("overflow.csv");
  const char* argv[] = {"zephyr",    "stability",      "overflow", "--out",
                        out.c_str(), "--max-int-bits", "12"};
  ASSERT_EQ(RunZephyr(7, argv), 0);
  const auto rows = ReadCsv(out);
  ASSERT_EQ(rows.size(), 11u * 2);  // I = 2..12, two forms
  for (const Row& r : rows) {
    const int intBits = std::stoi(r.at("int_bits"));
    if (intBits < 4) continue;  // the scan starts at D = 2: too far already for s2.16 naive
    const double extent = std::stod(r.at("max_extent_unflagged"));
    // Naive overflows near 2^(I/2) (|f|² = D²); Hearn-Baker only when D itself nears 2^I.
    if (r.at("form") == "naive") {
      EXPECT_LE(extent, std::exp2(intBits / 2.0 + 0.5)) << intBits;
      EXPECT_GE(extent, std::exp2(intBits / 2.0 - 1)) << intBits;
    } else {
      EXPECT_LE(extent, std::exp2(intBits)) << intBits;
      EXPECT_GE(extent, std::exp2(intBits - 1)) << intBits;
    }
  }
  std::filesystem::remove(out);
}

TEST(StabilityCommand, BadFormatIsAUserError) {
  const char* argv[] = {"zephyr", "stability", "distance", "--out", "-", "--formats", "float16"};
  EXPECT_NE(RunZephyr(7, argv), 0);
  const char* argv2[] = {"zephyr", "stability", "distance", "--out", "-", "--rays", "0"};
  EXPECT_NE(RunZephyr(7, argv2), 0);
  // An empty item is named, and a list of commas does not take the next flag as a format.
  for (const char* list : {",", "float32,,s15.16", "float32,"}) {
    const char* argv3[] = {"zephyr",    "stability", "distance", "--out", "-",
                           "--formats", list,        "--rays",   "4"};
    ::testing::internal::CaptureStderr();
    EXPECT_NE(RunZephyr(9, argv3), 0) << list;
    const std::string said = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(said.find("--formats '" + std::string(list) + "': an empty item"), std::string::npos)
        << said;
  }
}

}  // namespace
}  // namespace zephyr
