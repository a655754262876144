// Machine profiles as files (bitserial/profile.h; docs/bitserial.md, "Machine profiles"): the
// built-in ones are the repository's files, a file reads back to the profile it was written
// from, a user's copy gives the built-in's cycle report, an edit changes it as it says, and
// every kind of malformed file is refused at its line and column.
#include "bitserial/profile.h"

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "fixed/check.h"
#include "tests/farm/mpi_launch.h"

namespace zephyr::bitserial {
namespace {

using testing::RunZephyrProcess;
using testing::TempDir;

// The checkout: the nearest directory above the test binary holding bitserial/profiles.
std::filesystem::path Repo() {
  auto dir = std::filesystem::read_symlink("/proc/self/exe").parent_path();
  while (!dir.empty() && dir != dir.root_path() &&
         !std::filesystem::exists(dir / "bitserial/profiles"))
    dir = dir.parent_path();
  return dir;
}

std::string ReadText(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// The message of the UserError reading `text` throws ("" if it reads).
std::string ReadError(const std::string& text) {
  try {
    ProfileFromJson(text, "my.json");
  } catch (const UserError& e) {
    return e.what();
  }
  return "";
}

// "my.json:LINE:COLUMN: " of the first occurrence of `needle` in `text`.
// `skip` bytes further on.
std::string At(const std::string& text, const std::string& needle, size_t skip = 0) {
  const size_t found = text.find(needle);
  EXPECT_NE(found, std::string::npos) << needle;
  const size_t byte = found + skip;
  int line = 1, column = 1;
  for (size_t i = 0; i < byte; ++i) text[i] == '\n' ? (++line, column = 1) : ++column;
  return "my.json:" + std::to_string(line) + ":" + std::to_string(column) + ": ";
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

TEST(MachineProfiles, TheBuiltInsAreTheRepositorysFiles) {
  const auto dir = Repo() / "bitserial/profiles";
  ASSERT_TRUE(std::filesystem::exists(dir)) << dir;
  std::vector<std::string> files;
  for (const auto& f : std::filesystem::directory_iterator(dir))
    if (f.path().extension() == ".json") files.push_back(f.path().stem().string());
  std::sort(files.begin(), files.end());
  EXPECT_EQ(ProfileNames(), files);  // every file is built in, and nothing else
  for (const std::string& name : files) {
    EXPECT_EQ(BuiltInProfileText(name), ReadText(dir / (name + ".json"))) << name;
    EXPECT_EQ(Profile(name).name, name);  // a file's name is the name it is known by
  }
}

// FileText writes the layout of the files: a built-in profile written out is its file byte for
// byte, and a written profile with overrides reads back to the same numbers and sources.
TEST(MachineProfiles, AProfileWrittenOutReadsBackToItself) {
  for (const std::string& name : ProfileNames()) {
    const MachineProfile p = Profile(name);
    EXPECT_EQ(p.FileText(), BuiltInProfileText(name)) << name;
    MachineProfile q = p;
    q.Override("clockHz=12.5e6");
    q.Override("readExternal=3.25");
    q.Override("floatSubnormals=0");
    const MachineProfile r = ProfileFromJson(q.FileText(), "written.json");
    EXPECT_EQ(r.clockHz, 12.5e6);
    EXPECT_EQ(r.cost, q.cost);
    EXPECT_EQ(r.note, q.note);
    EXPECT_EQ(r.geometryNote, q.geometryNote);
    EXPECT_FALSE(r.floatSubnormals);
    EXPECT_EQ(r.physicalPes, q.physicalPes);
    ASSERT_EQ(r.shapes.size(), q.shapes.size());
    for (size_t k = 0; k < r.shapes.size(); ++k) EXPECT_EQ(r.shapes[k].extent, q.shapes[k].extent);
    EXPECT_EQ(r.FileText(), q.FileText());
  }
}

// Every entry of every built-in profile has a source: a citation, or "assumed: why".
TEST(MachineProfiles, EveryEntrySaysWhereItsValueComesFrom) {
  for (const std::string& name : ProfileNames()) {
    const MachineProfile p = Profile(name);
    std::vector<std::string> notes(p.note.begin(), p.note.end());
    notes.insert(notes.end(), p.geometryNote.begin(), p.geometryNote.end());
    notes.push_back(p.floatNote);
    for (const std::string& n : notes) {
      EXPECT_FALSE(n.empty()) << name;
      const bool cited =
          n.find("Batcher 1980") != std::string::npos || n.find("Blevins et al. 1990") == 0 ||
          n.find("paper §") == 0 || n.find("PIMeval") != std::string::npos ||
          n.find("pimParamsDDRDram.h") != std::string::npos || n.find("JEDEC") != std::string::npos;
      const bool marked = n.find("assumed") == 0 || n.find("unused") == 0;
      EXPECT_TRUE(cited || marked) << name << ": " << n;
    }
  }
}

// A user's file equal to a built-in one gives the built-in's cycle report; an edited file
// changes it as the edit says (external accesses twice as dear: the externalMemory class
// doubles and nothing else moves; the clock doubled: the modelled seconds halve).
TEST(MachineProfiles, AUsersFileChangesTheCycleReportAsItsEditSays) {
  TempDir dir;
  const std::string scene = testing::SmallSphereScene(dir);
  const std::string copy = dir / "copy.json", edited = dir / "edited.json";
  WriteText(copy, BuiltInProfileText("wavetracer"));
  std::string text = BuiltInProfileText("wavetracer");
  text = Replace(text, "\"readExternal\": {\"value\": 2,", "\"readExternal\": {\"value\": 4,");
  text = Replace(text, "\"writeExternal\": {\"value\": 2,", "\"writeExternal\": {\"value\": 4,");
  text = Replace(text, "\"clockHz\": {\"value\": 10000000,", "\"clockHz\": {\"value\": 20000000,");
  WriteText(edited, Replace(text, "\"name\": \"wavetracer\"", "\"name\": \"slow-external\""));
  auto cycles = [&](const std::string& machine) {
    const std::string report =
        dir / ("r-" + std::to_string(std::hash<std::string>()(machine)) + ".json");
    const auto r = RunZephyrProcess("render --no-progress --method simd " + scene + " --machine " +
                                    machine + " --report " + report);
    EXPECT_EQ(r.status, 0) << r.output;
    return nlohmann::json::parse(ReadText(report)).at("simd").at("cycles");
  };
  nlohmann::json builtIn = cycles("wavetracer"), mine = cycles(copy), slow = cycles(edited);
  EXPECT_EQ(mine.at("profileFile"), copy);
  mine.erase("profileFile");
  for (const char* timed : {"hostSeconds", "realTimeFactor"}) {  // the emulator's own speed
    EXPECT_TRUE(mine.contains(timed)) << timed;
    mine.erase(timed);
    builtIn.erase(timed);
  }
  EXPECT_EQ(mine, builtIn);
  EXPECT_EQ(slow.at("profile"), "slow-external");
  const auto& a = builtIn.at("byClass");
  const auto& b = slow.at("byClass");
  ASSERT_GT(a.at("externalMemory").get<double>(), 0);
  for (auto it = a.begin(); it != a.end(); ++it)
    EXPECT_EQ(b.at(it.key()).get<double>(),
              it.value().get<double>() * (it.key() == "externalMemory" ? 2 : 1))
        << it.key();
  const double extra = a.at("externalMemory").get<double>();
  EXPECT_EQ(slow.at("totalCycles").get<double>(), builtIn.at("totalCycles").get<double>() + extra);
  EXPECT_DOUBLE_EQ(slow.at("modelledSeconds").get<double>(),
                   slow.at("totalCycles").get<double>() / 20e6);
}

// Every value's line and column: replacing any entry's value by a string is refused at that
// string, naming the entry's path.
TEST(MachineProfiles, AWrongValueIsRefusedAtItsLineAndColumn) {
  const std::string base = BuiltInProfileText("wavetracer");
  const MachineProfile p = Profile("wavetracer");
  std::vector<std::string> keys = {"clockHz", "physicalPes", "internalBitsPerPe",
                                   "externalBitsPerPe", "floatSubnormals"};
  for (int i = 0; i < kMicroOpCount; ++i) keys.push_back(MicroOpName(static_cast<MicroOp>(i)));
  for (const std::string& key : keys) {
    const std::string head = "\"" + key + "\": {\"value\": ";
    const size_t at = base.find(head);
    ASSERT_NE(at, std::string::npos) << key;
    const size_t end = base.find(',', at + head.size());
    std::string text = base;
    text.replace(at + head.size(), end - at - head.size(), "\"fast\"");
    const std::string err = ReadError(text);
    EXPECT_EQ(err.find(At(text, "\"fast\"") + "entries." + key + ".value: expected a number"), 0)
        << err;
  }
}

// One test per kind of malformed file: the message names the file, the line and column, the
// key's path and what is wrong; nothing is defaulted.
TEST(MachineProfiles, EveryKindOfMalformedFileIsAClearError) {
  const std::string base = BuiltInProfileText("mpp");
  struct Case {
    const char* kind;
    std::string text;
    std::string want;
  };
  auto mutate = [&](const std::string& from, const std::string& to) {
    return Replace(base, from, to);
  };
  std::vector<Case> cases;
  {
    std::string t = mutate("\"hostPlane\": {", "\"hostPlane\": {,");
    cases.push_back({"invalid JSON", t, At(t, ",\"value\": 128") + "not valid JSON: syntax error"});
  }
  {
    std::string t = mutate("\"entries\": {", "\"speed\": 3,\n  \"entries\": {");
    cases.push_back(
        {"unknown top-level key", t, At(t, "\"speed\"") + "speed: unknown key (expected: name"});
  }
  {
    std::string t = mutate("\"meshHop\"", "\"meshhop\"");
    cases.push_back({"unknown entry", t, At(t, "\"meshhop\"") + "entries.meshhop: unknown key"});
  }
  {
    const size_t a = base.find("    \"reduceBit\"");
    std::string t = base;
    t.erase(a, base.find('\n', a) + 1 - a);
    cases.push_back(
        {"missing entry", t, At(t, "\"entries\": {", 11) + "entries.reduceBit: missing key"});
  }
  {
    std::string t = mutate("\"unit\": \"PEs\", ", "");
    cases.push_back({"missing unit", t,
                     At(t, "\"physicalPes\": {", 15) + "entries.physicalPes.unit: missing key"});
  }
  {
    std::string t = mutate("\"value\": 16384", "\"value\": true");
    cases.push_back({"wrong type", t,
                     At(t, "true") + "entries.physicalPes.value: expected a number, got boolean"});
  }
  {
    std::string t = mutate("\"unit\": \"Hz\"", "\"unit\": \"MHz\"");
    cases.push_back(
        {"wrong unit", t, At(t, "\"MHz\"") + "entries.clockHz.unit: expected \"Hz\", got \"MHz\""});
  }
  {
    std::string t = mutate("\"flagOp\": {\"value\": 1", "\"flagOp\": {\"value\": -1");
    cases.push_back(
        {"negative cost", t, At(t, "-1") + "entries.flagOp.value: expected a cost from 0"});
  }
  for (const char* pes : {"576", "0", "16384.5"}) {
    std::string t = mutate("\"value\": 16384", std::string("\"value\": ") + pes);
    cases.push_back({"PEs no multiple of 512", t,
                     At(t, std::string("\"value\": ") + pes, 9) +
                         "entries.physicalPes.value: expected a positive multiple of 512"});
  }
  {
    std::string t = mutate("\"value\": 1024", "\"value\": 1024.5");
    cases.push_back(
        {"fractional bits", t,
         At(t, "1024.5") + "entries.internalBitsPerPe.value: expected a whole number of bits"});
  }
  {
    std::string t = mutate("\"value\": 0, \"unit\": \"flag\"", "\"value\": 2, \"unit\": \"flag\"");
    cases.push_back(
        {"flag not 0 or 1", t,
         At(t, "2, \"unit\": \"flag\"") + "entries.floatSubnormals.value: expected 0 or 1"});
  }
  {
    std::string t = mutate("[\"128x128\"]", "[\"128x64\"]");
    cases.push_back({"shape of the wrong size", t,
                     At(t, "\"128x64\"") + "entries.meshShapes.value.0: the shape 128x64 has 8192 "
                                           "PEs, but physicalPes is 16384"});
  }
  {
    std::string t = mutate("[\"128x128\"]", "[\"128by128\"]");
    cases.push_back(
        {"malformed shape", t,
         At(t, "\"128by128\"") + "entries.meshShapes.value.0: expected a shape of 1 to 4"});
  }
  {
    std::string t = mutate("[\"128x128\"]", "[]");
    cases.push_back(
        {"no shape", t, At(t, "[]") + "entries.meshShapes.value: expected a list of mesh shapes"});
  }
  {
    std::string t = mutate("\"name\": \"mpp\"", "\"name\": \"My MPP\"");
    cases.push_back({"bad name", t, At(t, "\"My MPP\"") + "name: expected up to 40 characters"});
  }
  {
    std::string t = mutate("\"source\": \"Batcher 1980: 100 ns cycle\"", "\"source\": \"\"");
    cases.push_back(
        {"empty source", t, At(t, "\"\"") + "entries.clockHz.source: expected a non-empty string"});
  }
  {
    std::string t = "[1, 2]\n";
    cases.push_back(
        {"not an object", t, "my.json:1:1: (top level): expected an object, got array"});
  }
  for (const Case& c : cases) {
    const std::string err = ReadError(c.text);
    EXPECT_EQ(err.find(c.want), 0) << c.kind << "\n  got:  " << err << "\n  want: " << c.want;
  }
}

// The reader's second round of faults (issue 39): what crashed, hung, took a gigabyte or was
// silently read, each refused with a message (or, for a byte-order mark, read).
TEST(MachineProfiles, HostileFilesAreRefusedQuicklyAndNeverCrash) {
  const std::string base = BuiltInProfileText("mpp");
  // A UTF-8 byte-order mark before the JSON (some editors write one) reads as the file without.
  EXPECT_EQ(ProfileFromJson("\xEF\xBB\xBF" + base, "bom.json").FileText(),
            ProfileFromJson(base, "bom.json").FileText());
  // A number past a double, and a megabyte-scale run of digits: a clear error, not nlohmann's.
  EXPECT_NE(ReadError(Replace(base, "\"value\": 16384", "\"value\": 1e999"))
                .find("my.json: not valid JSON: number overflow"),
            std::string::npos);
  EXPECT_NE(ReadError(Replace(base, "\"value\": 16384", "\"value\": " + std::string(900000, '9')))
                .find("my.json: not valid JSON"),
            std::string::npos);
  // Deep nesting is refused before parsing, at the bracket past the bound; a file past the
  // size bound before anything is read.
  const std::string deep = std::string(40000, '[');
  EXPECT_EQ(ReadError(deep).find("my.json:1:" + std::to_string(kMaxProfileNesting + 1) +
                                 ": not a machine profile: nested more than"),
            0u)
      << ReadError(deep);
  EXPECT_NE(ReadError(std::string(kMaxProfileBytes + 1, ' ')).find("more than the 1024 KiB"),
            std::string::npos);
  // A key given twice is refused at its second place (nlohmann alone keeps the last).
  {
    const std::string t = Replace(base, "\"flagOp\": {\"value\": 1", "\"flagOp\": {\"value\": 1, \"value\": 7");
    EXPECT_EQ(ReadError(t).find(At(t, "\"value\": 7") + "entries.flagOp.value: this key appears twice"), 0u)
        << ReadError(t);
  }
  // A clock so slow every modelled time is infinite.
  EXPECT_NE(ReadError(Replace(base, "\"value\": 10000000", "\"value\": 1e-320")).find("entries.clockHz.value: expected a clock from 1 Hz"),
            std::string::npos)
      << Replace(base, "\"value\": 10000000", "\"value\": 1e-320").substr(0, 400);
  // A mesh shape whose product wraps a 32-bit int (8192 x 524289 = 2^32 + 8192).
  {
    const std::string t = Replace(Replace(base, "[\"128x128\"]", "[\"8192x524289\"]"),
                                  "\"value\": 16384", "\"value\": 8192");
    EXPECT_NE(ReadError(t).find("entries.meshShapes.value.0: expected a shape of 1 to 4 positive "
                                "extents such as \"64x128\", of at most 2^24 PEs"),
              std::string::npos)
        << ReadError(t);
  }
  // A NUL byte anywhere, even after a complete JSON value: nlohmann ends its input at the
  // first one (it read "0.5" and ignored the rest, and the key scanner then met an unopened
  // brace: the fuzzer's find), so it is refused at its line and column. The whole file too.
  for (const std::string& t : {std::string("0.5\0\0\"},\n}", 10), base + std::string(1, '\0'),
                               Replace(base, "\"value\": 16384", std::string("\"value\": 16\0" "384", 15))}) {
    const size_t nul = t.find('\0');
    int line = 1, column = 1;
    for (size_t i = 0; i < nul; ++i) t[i] == '\n' ? (++line, column = 1) : ++column;
    EXPECT_EQ(ReadError(t), "my.json:" + std::to_string(line) + ":" + std::to_string(column) +
                                ": a NUL byte (a text file holds none)");
  }
  // --set takes a plain decimal number only.
  MachineProfile p = Profile("wavetracer");
  for (const char* bad : {"clockHz=0x10", "clockHz= 5", "clockHz=inf", "clockHz=nan", "clockHz=",
                          "aluStep=1e999", "clockHz=5 "})
    EXPECT_THROW(p.Override(bad), UserError) << bad;
  EXPECT_NO_THROW(p.Override("clockHz=2.5e7"));
  EXPECT_EQ(p.clockHz, 2.5e7);
}

// A profile path that is no regular file is refused before it is opened: a FIFO would block.
TEST(MachineProfiles, APathThatIsNoRegularFileIsRefusedWithoutOpeningIt) {
  TempDir dir;
  const std::string fifo = dir / "p.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  auto error = [](const std::string& path) {
    try {
      Profile(path);
    } catch (const UserError& e) {
      return std::string(e.what());
    }
    return std::string("read");
  };
  EXPECT_EQ(error(fifo), fifo + ": is not a regular file (a device, pipe or socket), expected a "
                                "machine profile file (JSON)");
  const std::string folder = std::filesystem::path(dir / "x").parent_path().string();
  EXPECT_EQ(error(folder), folder + ": is a directory, expected a machine profile file (JSON)");
  EXPECT_NE(error("/dev/zero").find("is not a regular file"), std::string::npos);
}

TEST(MachineProfiles, AnUnknownNameOrAMissingFileIsAClearError) {
  const auto name = RunZephyrProcess("cycles --machine cray --op add");
  EXPECT_NE(name.status, 0);
  EXPECT_NE(name.output.find(
                "unknown machine profile 'cray' (built in: blitzen, mpp, pim-bitsimd-v-bank, "
                "wavetracer"),
            std::string::npos)
      << name.output;
  const auto file = RunZephyrProcess("cycles --machine /nonexistent/my.json --op add");
  EXPECT_NE(file.status, 0);
  EXPECT_NE(file.output.find(
                "/nonexistent/my.json: cannot open the machine profile file (no such file)"),
            std::string::npos)
      << file.output;
  // --set may not change the geometry a profile file fixes with its mesh shapes.
  MachineProfile p = Profile("wavetracer");
  EXPECT_THROW(p.Override("physicalPes=16384"), UserError);
}

// `zephyr profile show` prints a file that --machine reads; `profile list` names every built-in.
TEST(MachineProfiles, ProfileShowWritesAFileThatRenderReads) {
  TempDir dir;
  const auto shown =
      RunZephyrProcess("profile show blitzen --set clockHz=25e6 --out " + (dir / "b.json"));
  ASSERT_EQ(shown.status, 0) << shown.output;
  EXPECT_EQ(Profile(dir / "b.json").clockHz, 25e6);
  const auto cycles =
      RunZephyrProcess("cycles --machine " + (dir / "b.json") + " --op add --bits 32");
  EXPECT_NE(cycles.output.find("97 cycles per layer"), std::string::npos) << cycles.output;
  const auto list = RunZephyrProcess("profile list");
  for (const std::string& n : ProfileNames())
    EXPECT_NE(list.output.find(n + " "), std::string::npos) << list.output;
}

}  // namespace
}  // namespace zephyr::bitserial
