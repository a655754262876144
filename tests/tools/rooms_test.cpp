// docs/architecture.md's dependency picture, checked: every project include in hosts/ points
// down (hosts/cmd → methods → testbed → simd → trace → scene → fixed; methods → farm → io →
// fixed; simd → bitserial), so there is no cycle, the farm knows no pixel and the testbed
// knows no method.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>

namespace zephyr {
namespace {

// The rooms each room may include (itself included).
const std::map<std::string, std::set<std::string>>& Allowed() {
  static const std::map<std::string, std::set<std::string>> allowed = {
      {"hosts/io", {"fixed", "hosts/io"}},
      {"hosts/scene", {"fixed", "hosts/scene"}},
      {"hosts/trace", {"fixed", "hosts/io", "hosts/scene", "hosts/trace"}},
      {"hosts/simd", {"fixed", "bitserial", "hosts/io", "hosts/scene", "hosts/trace", "hosts/simd"}},
      {"hosts/farm", {"fixed", "hosts/io", "hosts/farm"}},
      {"hosts/testbed",
       {"fixed", "bitserial", "hosts/io", "hosts/scene", "hosts/trace", "hosts/simd",
        "hosts/testbed"}},
      {"hosts/methods",
       {"fixed", "bitserial", "hosts/io", "hosts/scene", "hosts/trace", "hosts/simd",
        "hosts/farm", "hosts/testbed", "hosts/methods"}},
      {"hosts/cmd",
       {"fixed", "bitserial", "hosts/io", "hosts/scene", "hosts/trace", "hosts/simd",
        "hosts/farm", "hosts/testbed", "hosts/methods", "hosts/cmd"}},
  };
  return allowed;
}

// "hosts/simd/pass.h" → "hosts/simd"; "fixed/check.h" → "fixed".
std::string RoomOf(const std::string& path) {
  const auto slash = path.find('/');
  if (path.rfind("hosts/", 0) == 0) return path.substr(0, path.find('/', slash + 1));
  return path.substr(0, slash);
}

TEST(Rooms, EveryIncludeInHostsPointsDown) {
  ASSERT_TRUE(std::filesystem::exists("hosts")) << "run from the repository's top folder";
  const std::regex include(R"re(^\s*#\s*include\s+"([^"]+)")re");
  int files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator("hosts")) {
    if (!entry.is_regular_file()) continue;
    const std::string path = entry.path().generic_string();
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
      if (top != "fixed" && top != "bitserial" && top != "hosts" && top != "tests" && top != "tools")
        continue;  // a library's header (Highway's are quoted as "hwy/...")
      EXPECT_TRUE(Allowed().at(room).count(RoomOf(target)))
          << path << ":" << number << ": " << room << " includes " << target;
    }
  }
  EXPECT_GT(files, 30);
}

}  // namespace
}  // namespace zephyr
