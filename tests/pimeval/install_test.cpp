// The drop-in library (docs/pim.md): `make install` into a temporary prefix puts
// include/libpimeval.h and lib/libpimeval.a where PIMbench's Makefile.common looks; a program
// written against PIMeval's API builds with exactly PIMbench's link line
// (g++ prog.cpp -std=c++17 -Wall -O3 -I... -L... -lpimeval) and runs; and, when
// ../shared/pimbench is there, the eight published programs build with their own Makefiles
// against that prefix (in a scratch copy: nothing is written under ../shared) and pass their own
// `-v t` check.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;

fs::path BuildDir() { return fs::read_symlink("/proc/self/exe").parent_path().parent_path(); }
fs::path RepoRoot() {
  fs::path p = BuildDir();
  while (!p.empty() && p != p.root_path() && !fs::exists(p / "Makefile")) p = p.parent_path();
  return p;
}
struct Shell {
  int status = -1;
  std::string output;
};
Shell RunShell(const std::string& command) {
  Shell r;
  FILE* pipe = ::popen(("{ " + command + " ; } 2>&1").c_str(), "r");
  if (!pipe) return r;
  char buffer[4096];
  while (size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) r.output.append(buffer, n);
  const int status = ::pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}
std::string Quote(const fs::path& p) { return "'" + p.string() + "'"; }

// One temporary prefix for the file's tests, installed once (as the install test does: the
// archives the test binary's build made, not rebuilt).
const fs::path& Prefix() {
  static fs::path prefix = [] {
    char pattern[] = "/tmp/zephyr_pim_install_XXXXXX";
    if (!::mkdtemp(pattern)) return fs::path();
    const fs::path p = fs::path(pattern) / "prefix";
    const Shell s = RunShell("make --no-print-directory -s -C " + Quote(RepoRoot()) +
                             " install PREFIX=" + Quote(p) + " BUILD=" + Quote(BuildDir()) +
                             " -o lib -o pimeval-lib");
    if (s.status != 0) {
      std::fprintf(stderr, "%s", s.output.c_str());
      return fs::path();
    }
    return p;
  }();
  return prefix;
}

const char* kProgram = R"(
#include <cstdio>
#include <vector>
#include "libpimeval.h"
int main() {
  if (pimCreateDevice(PIM_FUNCTIONAL, 1, 4, 32, 1024, 8192) != PIM_OK) return 1;
  const int n = 3000;
  std::vector<int> a(n), b(n), c(n);
  for (int i = 0; i < n; ++i) a[i] = i * 7 - 5000, b[i] = 1000 - i;
  PimObjId x = pimAlloc(PIM_ALLOC_AUTO, n, PIM_INT32), y = pimAllocAssociated(x, PIM_INT32);
  pimCopyHostToDevice(a.data(), x);
  pimCopyHostToDevice(b.data(), y);
  pimMax(x, y, y);
  int64_t sum = 0;
  pimRedSum(y, &sum);
  pimCopyDeviceToHost(y, c.data());
  int64_t want = 0;
  for (int i = 0; i < n; ++i) {
    if (c[i] != (a[i] > b[i] ? a[i] : b[i])) { std::printf("wrong at %d\n", i); return 1; }
    want += c[i];
  }
  std::printf("sum %lld expected %lld\n", (long long)sum, (long long)want);
  pimShowStats();
  return sum == want ? 0 : 1;
}
)";

TEST(PimInstall, AProgramBuildsWithPimbenchsExactLinkLineAndRuns) {
  const fs::path& prefix = Prefix();
  ASSERT_FALSE(prefix.empty()) << "make install failed";
  EXPECT_TRUE(fs::exists(prefix / "include" / "libpimeval.h"));
  EXPECT_TRUE(fs::exists(prefix / "lib" / "libpimeval.a"));
  const fs::path src = prefix.parent_path() / "prog";
  fs::create_directories(src);
  std::ofstream(src / "prog.cpp") << kProgram;
  const Shell build = RunShell("cd " + Quote(src) + " && g++ prog.cpp -std=c++17 -Wall -O3 -I" +
                               Quote(prefix / "include") + " -L" + Quote(prefix / "lib") +
                               " -lpimeval -o prog");
  ASSERT_EQ(build.status, 0) << build.output;
  EXPECT_EQ(build.output, "") << "warnings from the header";
  const Shell run = RunShell(Quote(src / "prog"));
  EXPECT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find("sum "), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("pimMax INT32"), std::string::npos) << run.output;
  const Shell uninstall = RunShell("make --no-print-directory -s -C " + Quote(RepoRoot()) +
                                   " uninstall PREFIX=" + Quote(prefix));
  EXPECT_EQ(uninstall.status, 0) << uninstall.output;
  EXPECT_FALSE(fs::exists(prefix / "lib" / "libpimeval.a"));
  EXPECT_FALSE(fs::exists(prefix / "include" / "libpimeval.h"));
  EXPECT_FALSE(fs::exists(prefix / "lib" / "libzephyr-pimeval.a"));
  fs::remove_all(prefix.parent_path());
}

// The eight PIMbench programs, their own Makefiles against a fresh install, each run with
// `-v t` at its default size (relu with -d 16: its default depth, 128, spends ~8 s in the
// program's own host loops, not in this library).
TEST(PimInstall, PimbenchProgramsBuildUnmodifiedAndPassTheirOwnCheck) {
  const fs::path shared = RepoRoot() / ".." / "shared" / "pimbench";
  if (!fs::exists(shared / "Makefile.common")) GTEST_SKIP() << shared << " is not there";
  char pattern[] = "/tmp/zephyr_pimbench_XXXXXX";
  ASSERT_NE(::mkdtemp(pattern), nullptr);
  const fs::path tmp = pattern, prefix = tmp / "prefix", copy = tmp / "pimbench";
  const Shell install = RunShell("make --no-print-directory -s -C " + Quote(RepoRoot()) +
                                 " install PREFIX=" + Quote(prefix) + " BUILD=" +
                                 Quote(BuildDir()) + " -o lib -o pimeval-lib");
  ASSERT_EQ(install.status, 0) << install.output;
  fs::copy(shared, copy, fs::copy_options::recursive);
  // Built two at a time (the compiles are most of this test's time).
  const Shell build = RunShell("cd " + Quote(copy / "PIMbench") +
                               " && ls -d */PIM | xargs -P 2 -I{} make --no-print-directory -s "
                               "-C {} LIBPIMEVAL_PATH=" + Quote(prefix));
  ASSERT_EQ(build.status, 0) << build.output;
  int programs = 0;
  for (const auto& dir : fs::directory_iterator(copy / "PIMbench")) {
    const fs::path pim = dir.path() / "PIM";
    if (!fs::exists(pim / "Makefile")) continue;
    SCOPED_TRACE(pim.string());
    ++programs;
    fs::path exe;
    for (const auto& f : fs::directory_iterator(pim))
      if (f.path().extension() == ".out") exe = f.path();
    ASSERT_FALSE(exe.empty());
    const std::string extra = dir.path().filename() == "relu" ? " -d 16" : "";
    const Shell run = RunShell("cd " + Quote(pim) + " && ./" + exe.filename().string() + " -v t" + extra);
    EXPECT_EQ(run.status, 0) << run.output;
    for (const char* bad : {"Wrong", "wrong", "Abort", "PIM-Error", "Incorrect", "Mismatch"})
      EXPECT_EQ(run.output.find(bad), std::string::npos) << bad << "\n" << run.output;
    EXPECT_NE(run.output.find("Modelled time:"), std::string::npos) << run.output;
  }
  EXPECT_EQ(programs, 8);
  fs::remove_all(tmp);
}

}  // namespace
