// docs/architecture.md's dependency picture, checked: every project include in hosts/ points
// down (hosts/cmd → methods → testbed → simd → trace → scene → fixed; methods → farm → io →
// fixed; simd → bitserial), so there is no cycle, the farm knows no pixel and the testbed
// knows no method.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace zephyr {
namespace {

// The rooms each room may include (itself included).
const std::map<std::string, std::set<std::string>>& Allowed() {
  static const std::map<std::string, std::set<std::string>> allowed = {
      {"fixed", {"fixed"}},
      {"bitserial", {"fixed", "bitserial"}},
      {"hosts/io", {"fixed", "hosts/io"}},
      {"hosts/scene", {"fixed", "hosts/scene"}},
      {"hosts/trace", {"fixed", "hosts/io", "hosts/scene", "hosts/trace"}},
      {"hosts/simd",
       {"fixed", "bitserial", "hosts/io", "hosts/scene", "hosts/trace", "hosts/simd"}},
      {"hosts/farm", {"fixed", "hosts/io", "hosts/farm"}},
      {"hosts/wavefront",
       {"fixed", "bitserial", "hosts/io", "hosts/scene", "hosts/trace", "hosts/simd",
        "hosts/wavefront"}},
      // The testbed prices counted work (TraceStats, cycle reports, the farm's times): it
      // needs neither the SIMD pass's code nor any method's.
      {"hosts/testbed",
       {"fixed", "bitserial", "hosts/io", "hosts/scene", "hosts/trace", "hosts/testbed"}},
      // The fidelity ledger sets published figures against the engine and the work table.
      {"hosts/ledger",
       {"fixed", "bitserial", "hosts/io", "hosts/scene", "hosts/trace", "hosts/testbed",
        "hosts/ledger"}},
      {"hosts/methods",
       {"fixed", "bitserial", "hosts/io", "hosts/scene", "hosts/trace", "hosts/simd", "hosts/farm",
        "hosts/testbed", "hosts/wavefront", "hosts/methods"}},
      {"hosts/cmd",
       {"fixed", "bitserial", "hosts/io", "hosts/scene", "hosts/trace", "hosts/simd", "hosts/farm",
        "hosts/testbed", "hosts/wavefront", "hosts/methods", "hosts/ledger", "hosts/cmd"}},
  };
  return allowed;
}

// "hosts/simd/pass.h" → "hosts/simd"; "fixed/check.h" → "fixed".
std::string RoomOf(const std::string& path) {
  const auto slash = path.find('/');
  if (path.rfind("hosts/", 0) == 0) return path.substr(0, path.find('/', slash + 1));
  return path.substr(0, slash);
}

TEST(Rooms, EveryIncludeOfTheEnginePointsDown) {
  ASSERT_TRUE(std::filesystem::exists("hosts")) << "run from the repository's top folder";
  const std::regex include(R"re(^\s*#\s*include\s+"([^"]+)")re");
  int files = 0;
  std::vector<std::filesystem::directory_entry> entries;
  for (const char* top : {"fixed", "bitserial", "hosts"})
    for (const auto& entry : std::filesystem::recursive_directory_iterator(top))
      entries.push_back(entry);
  for (const auto& entry : entries) {
    if (!entry.is_regular_file()) continue;
    const std::string path = entry.path().generic_string();
    if (path.find(".h") == std::string::npos && path.find(".cpp") == std::string::npos) continue;
    const std::string room = RoomOf(path);
    ASSERT_TRUE(Allowed().count(room)) << path << ": a room docs/architecture.md does not list";
    ++files;
    std::ifstream in(path);
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
      std::smatch m;
      if (!std::regex_search(line, m, include)) continue;
      const std::string target = m[1];
      const std::string top = target.substr(0, target.find('/'));
      if (top != "fixed" && top != "bitserial" && top != "hosts" && top != "tests" &&
          top != "tools")
        continue;  // a library's header (Highway's are quoted as "hwy/...")
      EXPECT_TRUE(Allowed().at(room).count(RoomOf(target)))
          << path << ":" << number << ": " << room << " includes " << target;
    }
  }
  EXPECT_GT(files, 60);
}

// The code of a file without its comments and with its string literals kept.
std::string CodeOf(const std::string& path) {
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string code;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '"') {  // a literal, whole (escapes kept)
      const size_t start = i;
      for (++i; i < text.size() && text[i] != '"'; ++i)
        if (text[i] == '\\') ++i;
      code += text.substr(start, i - start + 1);
    } else if (text.compare(i, 2, "//") == 0) {
      while (i < text.size() && text[i] != '\n') ++i;
      code += '\n';
    } else if (text.compare(i, 2, "/*") == 0) {
      i = text.find("*/", i);
      if (i == std::string::npos) break;
      ++i;
    } else {
      code += text[i];
    }
  }
  return code;
}

// The .h and .cpp files under `folders`, at any depth.
std::vector<std::string> SourcesUnder(std::initializer_list<const char*> folders) {
  std::vector<std::string> paths;
  for (const char* folder : folders)
    for (const auto& entry : std::filesystem::recursive_directory_iterator(folder)) {
      const std::string path = entry.path().generic_string();
      if (entry.is_regular_file() &&
          (path.find(".cpp") != std::string::npos || path.find(".h") != std::string::npos))
        paths.push_back(path);
    }
  return paths;
}

// Every file of `folders` whose code (comments removed, literals kept) matches `pattern`
// fails the test, with what matched and `why`; returns how many files were read.
int ExpectNoMatch(std::initializer_list<const char*> folders, const std::regex& pattern,
                  const std::string& why) {
  const std::vector<std::string> paths = SourcesUnder(folders);
  for (const std::string& path : paths) {
    const std::string code = CodeOf(path);
    std::smatch m;
    EXPECT_FALSE(std::regex_search(code, m, pattern))
        << path << ": '" << m.str() << "' (" << why << ")";
  }
  return int(paths.size());
}

// "The testbed knows no method" (docs/architecture.md): it takes counted work, so no code of
// hosts/testbed branches on a method or names one, but for `testbed calibrate`, which reads
// the report of a seq render.
TEST(Rooms, TheTestbedBranchesOnNoMethod) {
  const std::regex branch(R"re(\bmethod\s*[!=]=|[!=]=\s*method\b|"(simd|dist|hetero)")re");
  const int files = ExpectNoMatch({"hosts/testbed"}, branch, "the testbed prices counted work");
  EXPECT_GE(files, 4);
  // The check itself: it finds the branch the testbed had before it took counted work.
  const std::string before = "if (method == \"hetero\") x();";
  EXPECT_TRUE(std::regex_search(before, branch));
}

// Only the command line (and the methods, whose RenderOptions mirror render's flags one to
// one) names a flag in an error: a lower room's error names the value ("host threads must be
// 1..1024, got 0"); advice on what to type ("(use --number fixed)") may name one.
TEST(Rooms, NoRoomBelowTheMethodsMakesAFlagsError) {
  // A message that starts with a flag, or a flag followed by a colon ("--depth: ...").
  const std::regex flagError(R"re("--[a-z]|--[a-z][a-z-]*:)re");
  const int files =
      ExpectNoMatch({"fixed", "bitserial", "hosts/io", "hosts/scene", "hosts/trace", "hosts/simd",
                     "hosts/farm", "hosts/testbed", "hosts/wavefront"},
                    flagError, "a lower room names the value; hosts/cmd names the flag");
  EXPECT_GE(files, 60);
  // The check itself: it finds the errors these rooms had before.
  EXPECT_TRUE(std::regex_search(std::string(R"x(throw UserError("--threads: expected 1 to 8"))x"),
                                flagError));
  EXPECT_TRUE(
      std::regex_search(std::string(R"x(fmt::format("{} --frac-bits: more than"))x"), flagError));
  EXPECT_FALSE(std::regex_search(std::string(R"x(" (use --number fixed)")x"), flagError));
}

}  // namespace
}  // namespace zephyr
