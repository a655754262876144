// tools/mutants.json stays applicable as the code moves: every mutant names a file of the
// tree whose text holds its original exactly once (tools/mutants.sh applies it there), with a
// replacement that differs, under an id no other mutant has. A re-layout that moves the
// mutated line (as the SIMD pass's program leaving pass.cpp did) fails here, not silently in
// `make mutants`.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

namespace zephyr {
namespace {

std::string Text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

size_t Count(const std::string& text, const std::string& part) {
  size_t n = 0;
  for (size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
  return n;
}

TEST(Mutants, EveryMutantAppliesToExactlyOnePlace) {
  ASSERT_TRUE(std::filesystem::exists("tools/mutants.json"))
      << "run from the repository's top folder";
  const nlohmann::json all = nlohmann::json::parse(Text("tools/mutants.json"));
  const nlohmann::json& list = all.is_array() ? all : all.at("mutants");
  ASSERT_GT(list.size(), 50u);
  std::set<std::string> ids;
  for (const nlohmann::json& m : list) {
    const std::string id = m.at("id").get<std::string>(), file = m.at("file").get<std::string>();
    const std::string original = m.at("original").get<std::string>();
    EXPECT_TRUE(ids.insert(id).second) << id << ": the id is used twice";
    ASSERT_TRUE(std::filesystem::is_regular_file(file)) << id << ": no file " << file;
    EXPECT_EQ(Count(Text(file), original), 1u)
        << id << ": its original is not exactly once in " << file;
    EXPECT_NE(m.at("replacement").get<std::string>(), original) << id;
  }
}

}  // namespace
}  // namespace zephyr
