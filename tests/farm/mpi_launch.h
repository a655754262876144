// tests/farm/mpi_launch.h — running `build/.../zephyr` under mpirun from the tests.
//
// The zephyr program sits next to the test binary (both in $(BUILD)/bin), found through
// /proc/self/exe so the tests work from any build directory.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace zephyr::testing {

inline std::string ZephyrPath() {
  return (std::filesystem::read_symlink("/proc/self/exe").parent_path() / "zephyr").string();
}

struct Launch {
  int status = -1;     // exit status of the command
  std::string output;  // stdout and stderr together
};

// Runs a shell command line, capturing its output.
inline Launch RunCommand(const std::string& command) {
  Launch result;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return result;
  char buffer[4096];
  while (std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe))
    result.output.append(buffer, n);
  int raw = ::pclose(pipe);
  result.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
  return result;
}

// Runs `command` under `timeout`: a command still running after `seconds` is killed, and
// the output says so (status 124, or 137 after -k).
inline Launch RunWithTimeout(const std::string& command, int seconds) {
  Launch r = RunCommand("timeout -k 5 " + std::to_string(seconds) + " " + command);
  if (r.status == 124 || r.status == 137)
    r.output +=
        "\n[test] killed: not finished within " + std::to_string(seconds) + " s: " + command;
  return r;
}

// `mpirun -np ranks [env...] zephyr args` with the flags a 2-core test machine needs,
// killed after `seconds` (a stuck job fails the test with a message instead of hanging it).
inline Launch RunMpi(int ranks, const std::string& args, const std::string& env = "",
                     int seconds = 120) {
  return RunWithTimeout("mpirun --oversubscribe --allow-run-as-root -np " + std::to_string(ranks) +
                            " " + env + " " + ZephyrPath() + " " + args,
                        seconds);
}

inline Launch RunZephyrProcess(const std::string& args) {
  return RunWithTimeout(ZephyrPath() + " " + args, 120);
}

// A fresh directory per test under the system temp dir.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "zephyr-mpi-XXXXXX").string();
    std::vector<char> name(pattern.begin(), pattern.end());
    name.push_back('\0');
    path_ = ::mkdtemp(name.data());
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string operator/(const std::string& file) const { return (path_ / file).string(); }

 private:
  std::filesystem::path path_;
};

// A tmpfs of a few pages mounted on a fresh directory: a real full disk for the
// fault-injection tests (root only; Mounted() is false elsewhere and the tests skip).
// tmpfs counts whole 4 KiB pages of file data; empty files and directories cost none.
class TinyDisk {
 public:
  explicit TinyDisk(std::size_t bytes) { mounted_ = ::geteuid() == 0 && Resize(bytes, ""); }
  ~TinyDisk() {
    if (mounted_) RunCommand("umount " + dir_ / "");
  }
  bool Mounted() const { return mounted_; }
  // Grows or shrinks the disk in place (files stay).
  bool Resize(std::size_t bytes, const std::string& more = "remount,") {
    return RunCommand("mount -t tmpfs -o " + more + "size=" + std::to_string(bytes) + " tmpfs " +
                      dir_ / "")
               .status == 0;
  }
  std::string operator/(const std::string& file) const { return dir_ / file; }

 private:
  TempDir dir_;
  bool mounted_ = false;
};

// Fills `disk` to the last page with a file named `name`.
inline void FillDisk(const TinyDisk& disk, const std::string& name = "filler") {
  RunCommand("dd if=/dev/zero of=" + disk / name + " bs=4096 2>/dev/null");
}

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline nlohmann::json ReadJson(const std::string& path) {
  return nlohmann::json::parse(ReadFile(path));
}

// The render tests' scene: 12 random spheres, 40×30 pixels, written into `dir` as s.nff.
inline std::string SmallSphereScene(const TempDir& dir) {
  std::string path = dir / "s.nff";
  auto r = RunZephyrProcess("gen spheres --count 12 --seed 3 --size 40x30 --out " + path);
  EXPECT_EQ(r.status, 0) << r.output;
  return path;
}

// Kills child 1 (SIGKILL, via the test-only fault hook) after `framesBeforeKill` frames of
// `args` on 1 child, checks the job failed with the checkpoint `out`.frames left and no `out`,
// then reruns with --resume on 2 children and returns its status (0 expected). Both MPI
// tests of kill-and-resume (the farm alone, and the real render) share it.
inline Launch KillThenResume(const std::string& args, const std::string& out,
                             int framesBeforeKill) {
  auto killed = RunMpi(2, args, "-x ZEPHYR_TEST_FAULT=kill:1:" + std::to_string(framesBeforeKill));
  EXPECT_NE(killed.status, 0) << killed.output;
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_TRUE(std::filesystem::exists(out + ".frames")) << killed.output;
  return RunMpi(3, args + " --resume");
}

}  // namespace zephyr::testing
