// `make help` lists every target a user expects, each with its one-line comment.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace zephyr {
namespace {

// The repository root: the test binary is $(BUILD)/bin/zephyr_tests, BUILD under the root.
std::filesystem::path RepoRoot() {
  std::filesystem::path p = std::filesystem::read_symlink("/proc/self/exe").parent_path();
  while (!p.empty() && p != p.root_path() && !std::filesystem::exists(p / "Makefile"))
    p = p.parent_path();
  return p;
}

TEST(BuildHelp, ListsEveryTargetWithItsComment) {
  const std::filesystem::path root = RepoRoot();
  ASSERT_TRUE(std::filesystem::exists(root / "Makefile")) << root;
  std::string command = "make --no-print-directory -s -C '" + root.string() + "' help 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char buffer[4096];
  while (size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
  ASSERT_EQ(::pclose(pipe), 0) << output;
  for (const char* target :
       {"all", "test", "run", "bench", "charts", "clean", "help", "fuzz", "mutants"}) {
    const std::string line = std::string("make ") + target + " ";
    size_t at = output.find(line);
    ASSERT_NE(at, std::string::npos) << "make help does not list '" << target << "':\n" << output;
    size_t end = output.find('\n', at);
    EXPECT_GT(end - at, line.size() + 10) << "no comment for " << target << ":\n" << output;
  }
  EXPECT_EQ(output.find("Makefile"), std::string::npos) << "file names leaked:\n" << output;
}

}  // namespace
}  // namespace zephyr
