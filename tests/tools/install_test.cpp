// `make install` (docs/programming.md, "Building a program on the library"): into a
// temporary prefix, the headers a program includes compile from there alone (none reaches
// an uninstalled header), tools/examples/life copied out of the tree builds with the
// pkg-config file and nothing else, and prints what the in-tree build/bin/example_life
// prints; `make uninstall` removes every installed file.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace zephyr {
namespace {

namespace fs = std::filesystem;

// The test binary is $(BUILD)/bin/zephyr_tests; the repository root is the first parent
// holding the Makefile.
fs::path BuildDir() { return fs::read_symlink("/proc/self/exe").parent_path().parent_path(); }
fs::path RepoRoot() {
  fs::path p = BuildDir();
  while (!p.empty() && p != p.root_path() && !fs::exists(p / "Makefile")) p = p.parent_path();
  return p;
}

struct Shell {
  int status = -1;
  std::string output;  // stdout and stderr
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

TEST(ToolsInstall, LifeBuiltOutOfTreeWithPkgConfigPrintsWhatTheInTreeBuildPrints) {
  const fs::path root = RepoRoot(), build = BuildDir();
  ASSERT_TRUE(fs::exists(root / "Makefile")) << root;
  const fs::path archive = build / "lib" / "libzephyr-bitserial.a";
  const fs::path inTree = build / "bin" / "example_life";
  // Both are built with the tests (the Makefile's order-only prerequisites of zephyr_tests).
  ASSERT_TRUE(fs::exists(archive)) << archive << " is missing: `make lib` builds it";
  ASSERT_TRUE(fs::exists(inTree)) << inTree << " is missing: `make` builds it";

  char pattern[] = "/tmp/zephyr_install_test_XXXXXX";
  ASSERT_NE(::mkdtemp(pattern), nullptr);
  const fs::path tmp = pattern, prefix = tmp / "prefix", src = tmp / "src";
  // -o lib: install the archive as built (its objects are the test binary's own), without
  // looking at them: this make may have other compiler flags than the build's, and would
  // rebuild the engine.
  const Shell install =
      RunShell("make --no-print-directory -s -C " + Quote(root) +
               " install PREFIX=" + Quote(prefix) + " BUILD=" + Quote(build) + " -o lib");
  ASSERT_EQ(install.status, 0) << install.output;
  EXPECT_NE(install.output.find("installed"), std::string::npos) << install.output;
  const fs::path pc = prefix / "lib" / "pkgconfig" / "zephyr-bitserial.pc";
  ASSERT_TRUE(fs::exists(pc));
  EXPECT_TRUE(fs::exists(prefix / "lib" / "libzephyr-bitserial.a"));
  EXPECT_TRUE(fs::exists(prefix / "include" / "zephyr" / "bitserial" / "multi.h"));
  // The engine's internal headers stay in the tree (the Makefile's PUBLIC_HEADERS says why).
  EXPECT_FALSE(fs::exists(prefix / "include" / "zephyr" / "bitserial" / "internals.h"));
  EXPECT_FALSE(fs::exists(prefix / "include" / "zephyr" / "bitserial" / "serial.h"));
  std::error_code noProfiles;  // the tree may have no profile files yet
  for (const auto& f : fs::directory_iterator(root / "bitserial" / "profiles", noProfiles))
    EXPECT_TRUE(fs::exists(prefix / "share" / "zephyr" / "profiles" / f.path().filename()))
        << f.path();

  const std::string env =
      "cd " + Quote(src) + " && export PKG_CONFIG_PATH=" + Quote(pc.parent_path()) + " && ";
  fs::create_directories(src);
  // Every installed header at once, from the prefix only: one that includes a header the
  // install left out does not compile.
  {
    std::ofstream all(src / "all_headers.cpp");
    for (const auto& f : fs::recursive_directory_iterator(prefix / "include" / "zephyr"))
      if (f.path().extension() == ".h")
        all << "#include <" << fs::relative(f.path(), prefix / "include" / "zephyr").string()
            << ">\n";
  }
  const Shell headers = RunShell(env +
                                 "g++ -std=c++20 -fsyntax-only all_headers.cpp $(pkg-config "
                                 "--cflags zephyr-bitserial)");
  EXPECT_EQ(headers.status, 0) << headers.output;

  // docs/programming.md's command, on the two files of the example and nothing else.
  fs::copy_file(root / "tools" / "examples" / "life.cpp", src / "life.cpp");
  fs::copy_file(root / "tools" / "examples" / "life.h", src / "life.h");
  const Shell compile = RunShell(env +
                                 "g++ -std=c++20 life.cpp -o life $(pkg-config --cflags --libs "
                                 "zephyr-bitserial)");
  ASSERT_EQ(compile.status, 0) << compile.output;
  const std::string args = " --size 128 --generations 5 --seed 7";
  const Shell outside = RunShell(Quote(src / "life") + args);
  const Shell inside = RunShell(Quote(inTree) + args);
  ASSERT_EQ(inside.status, 0) << inside.output;
  EXPECT_EQ(outside.status, 0) << outside.output;
  EXPECT_NE(inside.output.find("equal to the plain C++ version"), std::string::npos);
  EXPECT_EQ(outside.output, inside.output);

  const Shell uninstall = RunShell("make --no-print-directory -s -C " + Quote(root) +
                                   " uninstall PREFIX=" + Quote(prefix) + " BUILD=" + Quote(build));
  EXPECT_EQ(uninstall.status, 0) << uninstall.output;
  EXPECT_FALSE(fs::exists(prefix / "include" / "zephyr"));  // PREFIX/include itself stays
  EXPECT_FALSE(fs::exists(pc));
  EXPECT_FALSE(fs::exists(prefix / "lib" / "libzephyr-bitserial.a"));
  EXPECT_FALSE(fs::exists(prefix / "share" / "zephyr"));
  fs::remove_all(tmp);
}

// What a packager and a careless user do (issues 39 and 40): a staged install (DESTDIR) names the
// final prefix in the pkg-config file; a prefix with spaces or a quote installs into exactly
// that folder and nothing outside it; an empty, relative or root prefix is refused; uninstall
// removes only files under the prefix, whatever its list says.
TEST(ToolsInstall, StagedQuotedAndHostilePrefixesInstallExactlyWhereTheySay) {
  const fs::path root = RepoRoot(), build = BuildDir();
  ASSERT_TRUE(fs::exists(build / "lib" / "libzephyr-bitserial.a"));
  char pattern[] = "/tmp/zephyr_install_test_XXXXXX";
  ASSERT_NE(::mkdtemp(pattern), nullptr);
  const fs::path tmp = pattern;
  auto make = [&](const std::string& target, const std::string& vars) {
    return RunShell("make --no-print-directory -s -C " + Quote(root) + " " + target + " " + vars +
                    " BUILD=" + Quote(build) + " -o lib");
  };
  // A staged install: every file under DESTDIR/usr, the .pc file saying prefix=/usr.
  const fs::path stage = tmp / "stage";
  Shell r = make("install", "DESTDIR=" + Quote(stage) + " PREFIX=/usr");
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream pc(stage / "usr/lib/pkgconfig/zephyr-bitserial.pc");
  std::string first;
  std::getline(pc, first);
  EXPECT_EQ(first, "prefix=/usr");
  EXPECT_TRUE(fs::exists(stage / "usr/lib/libzephyr-bitserial.a"));
  r = make("uninstall", "DESTDIR=" + Quote(stage) + " PREFIX=/usr");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_FALSE(fs::exists(stage / "usr/lib/libzephyr-bitserial.a"));

  // Spaces and a quote: one folder of exactly that name, and nothing else created under tmp.
  for (const std::string name : {"my prefix", "it's here", "a\"b"}) {
    const fs::path prefix = tmp / name;
    // The value quoted for the shell that runs make: ' as '\''.
    std::string quoted = "'";
    for (char c : prefix.string()) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    quoted += "'";
    r = make("install", "PREFIX=" + quoted);
    ASSERT_EQ(r.status, 0) << name << "\n" << r.output;
    EXPECT_TRUE(fs::exists(prefix / "lib/libzephyr-bitserial.a")) << name << "\n" << r.output;
    EXPECT_TRUE(fs::exists(prefix / "share/zephyr/installed-files")) << name;
    r = make("uninstall", "PREFIX=" + quoted);
    EXPECT_EQ(r.status, 0) << name << "\n" << r.output;
    EXPECT_FALSE(fs::exists(prefix / "lib/libzephyr-bitserial.a")) << name;
  }
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(tmp)) ++entries;
  EXPECT_EQ(entries, 4) << "stage and the three prefixes, nothing beside them";

  // Refused before anything is written.
  for (const std::string& bad : {std::string("PREFIX="), std::string("PREFIX=relative/dir"),
                                 std::string("PREFIX=/")}) {
    r = make("install", bad);
    EXPECT_NE(r.status, 0) << bad << "\n" << r.output;
    EXPECT_NE(r.output.find("PREFIX"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(root / "relative"));

  // An installed-files list with a line outside the prefix: that file is left alone.
  const fs::path prefix = tmp / "p", outside = tmp / "keep.txt";
  r = make("install", "PREFIX=" + Quote(prefix));
  ASSERT_EQ(r.status, 0) << r.output;
  std::ofstream(outside) << "mine";
  std::ofstream(prefix / "share/zephyr/installed-files", std::ios::app)
      << "../keep.txt\n" << outside.string() << "\n";
  r = make("uninstall", "PREFIX=" + Quote(prefix));
  EXPECT_NE(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("is not a path under the prefix"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(outside));
  EXPECT_FALSE(fs::exists(prefix / "lib/libzephyr-bitserial.a"));
  fs::remove_all(tmp);
}

}  // namespace
}  // namespace zephyr
