// `make charts` end to end in its QUICK mode (tools/charts.sh): the sweeps run with whatever
// methods the zephyr program has, and every CSV and PNG the docs cite is written and holds
// data — now with all four methods and `zephyr accuracy`, every cell measured. Keeps the chart tool
// chain working while the methods change.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// The repository root: the working directory under `make test`, else found upward from
// the test binary (build/.../bin/zephyr_tests).
fs::path RepoRoot() {
  for (fs::path p = fs::current_path(); !p.empty(); p = p.parent_path()) {
    if (fs::exists(p / "tools/charts.sh")) return p;
    if (p == p.root_path()) break;
  }
  for (fs::path p = fs::read_symlink("/proc/self/exe").parent_path(); !p.empty();
       p = p.parent_path()) {
    if (fs::exists(p / "tools/charts.sh")) return p;
    if (p == p.root_path()) break;
  }
  return {};
}

int CountDataRows(const fs::path& csv) {
  std::ifstream f(csv);
  std::string line;
  int rows = -1;  // the header
  while (std::getline(f, line)) rows += !line.empty();
  return rows;
}

bool IsPng(const fs::path& png) {
  std::ifstream f(png, std::ios::binary);
  char magic[8] = {};
  f.read(magic, 8);
  return f && std::string(magic + 1, 3) == "PNG" && fs::file_size(png) > 1000;
}

TEST(ChartsQuick, EverySweepWritesItsCsvAndChart) {
  const fs::path root = RepoRoot();
  ASSERT_FALSE(root.empty()) << "tools/charts.sh not found";
  const fs::path zephyr = fs::read_symlink("/proc/self/exe").parent_path() / "zephyr";
  ASSERT_TRUE(fs::exists(zephyr)) << zephyr << " not built";
  const fs::path out = fs::temp_directory_path() / ("zephyr_charts_" + std::to_string(getpid()));
  fs::remove_all(out);
  const std::string cmd = "QUICK=1 ZEPHYR='" + zephyr.string() + "' OUT='" + out.string() +
                          "' bash '" + (root / "tools/charts.sh").string() + "' > '" +
                          (out.string() + ".log") + "' 2>&1";
  const int status = std::system(cmd.c_str());
  if (status != 0) {
    std::ifstream log(out.string() + ".log");
    ADD_FAILURE() << "charts.sh failed:\n" << std::string(std::istreambuf_iterator<char>(log), {});
  }
  ASSERT_EQ(status, 0);

  // QUICK: 2 object counts, 2 frame sizes; the stability scans have many rows.
  const struct {
    const char* csv;
    int minRows;
  } tables[] = {{"fig05_seq_vs_simd", 2},
                {"fig06_seq_vs_dist", 2},
                {"fig07_hetero_vs_dist_2children", 2},
                {"fig10_data_flow", 2},
                {"fig11_pixels", 2},
                {"fig12_all_methods", 2},
                {"stability_distance", 100},
                {"stability_overflow", 10},
                {"runs", 2},
                {"recompute_share", 8}};  // 2 scenes x 2 policies x 2 widths
  for (const auto& t : tables) {
    const fs::path csv = out / (std::string(t.csv) + ".csv");
    ASSERT_TRUE(fs::exists(csv)) << csv;
    EXPECT_GE(CountDataRows(csv), t.minRows) << csv;
  }
  for (const char* png :
       {"fig05_seq_vs_simd", "fig06_seq_vs_dist", "fig07_hetero_vs_dist_2children",
        "fig10_data_flow", "fig11_pixels", "fig12_all_methods", "stability_wrong_hits",
        "stability_t_error", "stability_overflow", "speed_vs_accuracy_pct_wrong",
        "speed_vs_accuracy_t_error", "speed_vs_accuracy_psnr", "uncertain_pixels",
        "recompute_share"})
    EXPECT_TRUE(IsPng(out / (std::string(png) + ".png"))) << png;
  // Every method has landed: each figure's every cell is a measured number (no NaN), the
  // times positive; the farm figures count bytes and pixels.
  for (const char* csv :
       {"fig05_seq_vs_simd", "fig06_seq_vs_dist", "fig07_hetero_vs_dist_2children",
        "fig10_data_flow", "fig11_pixels", "fig12_all_methods"}) {
    std::ifstream f(out / (std::string(csv) + ".csv"));
    std::string line;
    std::getline(f, line);  // header
    while (std::getline(f, line)) {
      std::stringstream cells(line);
      std::string cell;
      std::getline(cells, cell, ',');  // the x value
      for (int column = 2; std::getline(cells, cell, ','); ++column) {
        ASSERT_NE(cell, "NaN") << csv << " column " << column << ": " << line;
        EXPECT_GT(std::stod(cell), 0) << csv << " column " << column << ": " << line;
      }
    }
  }
  // Hetero skips degenerate frames: at 16x16 frames of a 64x64 image with 8 spheres it
  // processes no more pixels than dist, which processes every one of the 4096.
  {
    std::ifstream f(out / "fig11_pixels.csv");
    std::string line;
    std::getline(f, line);
    while (std::getline(f, line)) {
      std::stringstream cells(line);
      std::string frame, dist, hetero;
      std::getline(cells, frame, ',');
      std::getline(cells, dist, ',');
      std::getline(cells, hetero, ',');
      EXPECT_EQ(std::stod(dist), 64 * 64) << line;
      EXPECT_LE(std::stod(hetero), 64 * 64) << line;
    }
  }
  // The accuracy sweep has zephyr accuracy's figures: a PSNR for every fixed width, and the
  // error falls as the fraction widens.
  {
    std::ifstream f(out / "accuracy.csv");
    std::string line;
    std::getline(f,
                 line);  // kind,frac_bits,cycles,host_s,pct_wrong,t_err_max,t_err_mean,psnr,planned
    int fixedRows = 0;
    double firstTErr = -1, lastTErr = -1;
    std::map<std::string, double> floatTErr;  // the sequential tracers, against the same reference
    while (std::getline(f, line)) {
      std::vector<std::string> c;
      std::stringstream cells(line);
      for (std::string cell; std::getline(cells, cell, ',');) c.push_back(cell);
      ASSERT_EQ(c.size(), 9u) << line;
      if (c[0] == "float32" || c[0] == "float64") {
        ASSERT_NE(c[5], "NaN") << line;  // measured by zephyr accuracy --method seq
        ASSERT_NE(c[4], "NaN") << line;
        floatTErr[c[0]] = std::stod(c[5]);
        continue;
      }
      if (c[0] != "fixed" || c[8] == "1") continue;
      ++fixedRows;
      ASSERT_NE(c[7], "NaN") << line;
      ASSERT_NE(c[5], "NaN") << line;
      if (firstTErr < 0) firstTErr = std::stod(c[5]);
      lastTErr = std::stod(c[5]);
    }
    EXPECT_EQ(fixedRows, 3);  // QUICK widths 4, 8, 16
    EXPECT_LT(lastTErr, firstTErr);
    ASSERT_EQ(floatTErr.size(), 2u) << "float32 and float64 points missing from accuracy.csv";
    EXPECT_LT(floatTErr["float64"], floatTErr["float32"]);
  }
  // The recompute share (tools/charts/recompute.sh): with --uncertain recompute the host's
  // share falls as the fraction widens, and auto (refine first) never recomputes more pixels
  // than recompute at the same width.
  {
    std::ifstream f(out / "recompute_share.csv");
    std::string line;
    std::getline(f, line);  // scene,policy,frac_bits,cycles,refine_cycles,refined,recomputed,...
    std::map<std::string, std::map<int, double>> pct;  // scene/policy -> width -> % recomputed
    std::map<std::string, double> recomputed;          // scene/policy/width -> pixels
    while (std::getline(f, line)) {
      std::vector<std::string> c;
      std::stringstream cells(line);
      for (std::string cell; std::getline(cells, cell, ',');) c.push_back(cell);
      ASSERT_EQ(c.size(), 10u) << line;
      EXPECT_GT(std::stod(c[3]), 0) << line;  // cycles of the first pass
      pct[c[0] + "/" + c[1]][std::stoi(c[2])] = std::stod(c[7]);
      recomputed[c[0] + "/" + c[1] + "/" + c[2]] = std::stod(c[6]);
    }
    for (const char* scene : {"spheres64", "showcase"}) {
      const auto& r = pct[std::string(scene) + "/recompute"];
      ASSERT_EQ(r.size(), 2u) << scene;  // QUICK widths 8, 16
      EXPECT_LT(r.at(16), r.at(8)) << scene;
      for (int b : {8, 16}) {
        const std::string w = "/" + std::to_string(b);
        EXPECT_LE(recomputed[scene + std::string("/auto") + w],
                  recomputed[scene + std::string("/recompute") + w])
            << scene << " at " << b << " bits";
      }
    }
  }
  fs::remove_all(out);
  fs::remove(out.string() + ".log");
}

}  // namespace
