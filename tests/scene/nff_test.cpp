// Tests for the NFF reader, its error reports and the scene generators.
#include "hosts/scene/nff.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "fixed/check.h"
#include "hosts/scene/gen.h"

namespace zephyr {
namespace {

const char* kView =
    "b 0.1 0.2 0.3\nv\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 30\nhither 0.01\nresolution 64 48\n";

std::vector<std::string> Errors(const std::string& text) {
  std::vector<std::string> errors;
  EXPECT_FALSE(ParseNff(text, "t.nff", errors).has_value()) << text;
  return errors;
}

TEST(SceneNff, ReadsEveryKeyword) {
  const std::string text = std::string(kView) +
                           "l 1 2 3\nl 4 5 6 0.5 0.25 1\n"
                           "f 1 0.5 0 0.7 0.3 20 0.1 1.5\n"
                           "s 1 2 3 0.5\n"
                           "c 0 0 0 1 0 0 2 0.5\n"      // cone on one line, as SPD jacks writes it
                           "c\n1 1 1 0.3\n1 1 3 0.3\n"  // cylinder on two lines
                           "# a comment\n"
                           "p 3\n0 0 0\n1 0 0\n0 1 0\n"
                           "pp 3\n0 0 1 0 0 1\n1 0 1 0 0 2\n0 1 1 0 0 1\n";
  std::vector<std::string> errors;
  auto scene = ParseNff(text, "t.nff", errors);
  ASSERT_TRUE(scene) << (errors.empty() ? "" : errors[0]);
  EXPECT_EQ(scene->camera.width, 64);
  EXPECT_EQ(scene->camera.height, 48);
  EXPECT_DOUBLE_EQ(scene->camera.angleDegrees, 30);
  EXPECT_EQ(scene->background, (Vec3{0.1, 0.2, 0.3}));
  ASSERT_EQ(scene->lights.size(), 2u);
  EXPECT_EQ(scene->lights[0].colour, (Vec3{1, 1, 1}));
  EXPECT_EQ(scene->lights[1].colour, (Vec3{0.5, 0.25, 1}));
  ASSERT_EQ(scene->materials.size(), 1u);
  EXPECT_DOUBLE_EQ(scene->materials[0].ior, 1.5);
  ASSERT_EQ(scene->objects.size(), 5u);
  EXPECT_EQ(scene->objects[0].Kind(), ShapeKind::kSphere);
  EXPECT_EQ(scene->objects[1].Kind(), ShapeKind::kCone);
  EXPECT_EQ(std::get<Cone>(scene->objects[2].shape).apex, (Vec3{1, 1, 3}));
  EXPECT_EQ(scene->objects[3].Kind(), ShapeKind::kPolygon);
  const auto& pp = std::get<Polygon>(scene->objects[4].shape);
  ASSERT_EQ(pp.normals.size(), 3u);
  EXPECT_EQ(pp.normals[1], (Vec3{0, 0, 1}));  // normalised
  EXPECT_EQ(scene->objects[0].where.line, 12);
  EXPECT_EQ(scene->objects[0].where.column, 1);
}

TEST(SceneNff, TransformAppliesToFollowingObjectsUntilIdentity) {
  const std::string text = std::string(kView) +
                           "f 1 1 1 1 0 0 0 1\n"
                           "transform 2 0 0 1  0 1 0 2  0 0 1 3\ns 0 0 0 1\ns 1 1 1 1\n"
                           "transform identity\ns 0 0 0 1\n";
  std::vector<std::string> errors;
  auto scene = ParseNff(text, "t.nff", errors);
  ASSERT_TRUE(scene);
  ASSERT_TRUE(scene->objects[0].transform);
  ASSERT_TRUE(scene->objects[1].transform);
  EXPECT_FALSE(scene->objects[2].transform);
  EXPECT_EQ(scene->objects[0].transform->ApplyPoint({1, 1, 1}), (Vec3{3, 3, 4}));
}

TEST(SceneNff, ErrorsCarryFileLineColumnAndAreAllCollected) {
  const auto errors = Errors(std::string(kView) +
                             "f 1 1 1 1 0 0 0 1\n"
                             "s 0 0 0 -1\n"   // line 10
                             "  bogus 1 2\n"  // line 11, column 3
                             "s 0 0 nan 1\n"  // line 12, column 7
                             "s 1 1 1 0\n");
  ASSERT_EQ(errors.size(), 4u);
  EXPECT_NE(errors[0].find("t.nff:10:1: expected a sphere radius > 0"), std::string::npos)
      << errors[0];
  EXPECT_NE(errors[1].find("t.nff:11:3: unknown keyword 'bogus'"), std::string::npos) << errors[1];
  EXPECT_NE(errors[2].find("t.nff:12:7: expected a finite number"), std::string::npos) << errors[2];
  EXPECT_NE(errors[3].find("t.nff:13:1:"), std::string::npos) << errors[3];
}

TEST(SceneNff, RejectsBadScenes) {
  auto has = [](const std::vector<std::string>& errors, const std::string& what) {
    for (const auto& e : errors)
      if (e.find(what) != std::string::npos) return true;
    return false;
  };
  const std::string f = "f 1 1 1 1 0 0 0 1\n";
  EXPECT_TRUE(has(Errors(f + "s 0 0 0 1\n"), "missing 'v'"));
  EXPECT_TRUE(has(Errors(std::string(kView) + "s 0 0 0 1\n"), "before any material"));
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "s 0 0 1e999 1\n"), "finite number"));
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "s 0 0 inf 1\n"), "finite number"));
  {
    std::vector<std::string> errors;
    auto scene =
        ParseNff(std::string(kView) + f + "p 3\n0 0 0\n1 1 1\n2 2 2\ns 0 0 0 1\n", "t.nff", errors);
    ASSERT_TRUE(scene);
    EXPECT_EQ(scene->objects.size(), 1u);  // the zero-area polygon is dropped, loudly
    ASSERT_EQ(scene->warnings.size(), 1u);
    EXPECT_NE(scene->warnings[0].find("t.nff:10:1: warning: degenerate polygon"),
              std::string::npos);
  }
  EXPECT_TRUE(
      has(Errors(std::string(kView) + f + "p 4\n0 0 0\n1 0 0\n1 1 0.5\n0 1 0\n"), "non-planar"));
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "p 2\n0 0 0\n1 0 0\n"), "integer from 3"));
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "transform 1 0 0 0 2 0 0 0 0 0 0 0\ns 0 0 0 1\n"),
                  "singular transform"));
  // Singular or not does not depend on the matrix's scale: tiny and huge uniform
  // scales are regular, a rank-2 map is singular at any scale.
  for (const char* k : {"1e-120", "1e-152", "1e100", "1e120"}) {
    const std::string e(k);
    std::vector<std::string> errors;
    EXPECT_TRUE(ParseNff(std::string(kView) + f + "transform " + e + " 0 0 0 0 " + e + " 0 0 0 0 " +
                             e + " 0\n" + "transform identity\ns 0 0 0 1\n",
                         "t.nff", errors))
        << k << ": " << errors[0];
    EXPECT_TRUE(
        has(Errors(std::string(kView) + f + "transform " + e + " 0 0 0 0 " + e + " 0 0 " + e +
                   " 0 0 0\n"
                   "s 0 0 0 1\n"),
            "singular transform"))
        << k;
  }
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "c 0 0 0 1 0 0 0 1\n"), "different points"));
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "s 0 0 0\n"), "unexpected end of file"));
  EXPECT_TRUE(has(
      Errors(
          "b 0 0 0\nv\nfrom 0 0 1\nat 0 0 0\nup 0 1 0\nangle 30\nhither 0\nresolution 100000 5\n"),
      "integer from 1 to 16384"));
  EXPECT_TRUE(has(
      Errors("b 0 0 0\nv\nfrom 0 0 1\nat 0 0 0\nup 0 0 1\nangle 30\nhither 0\nresolution 5 5\n"),
      "parallel"));
  EXPECT_TRUE(has(Errors(std::string(kView) + "angle 40\n"), "given twice"));
}

TEST(SceneNff, ThrowingReaderListsEveryErrorOnce) {
  try {
    ParseNffOrThrow(std::string(kView) + "f 1 1 1 1 0 0 0 1\nq\nz\n", "x.nff");
    FAIL() << "expected a UserError";
  } catch (const UserError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("2 errors"), std::string::npos) << m;
    EXPECT_NE(m.find("x.nff:10:1: unknown keyword 'q'"), std::string::npos) << m;
    EXPECT_NE(m.find("x.nff:11:1: unknown keyword 'z'"), std::string::npos) << m;
  }
  EXPECT_THROW(ReadNffFile("/nonexistent/scene.nff"), UserError);
}

// Issue 11: LF, CRLF and a lone CR all end a line (comments end there too, line numbers
// count them), and a leading UTF-8 byte-order mark is skipped.
TEST(SceneNff, EveryLineEndingEndsALineAndABomIsSkipped) {
  const std::string lines[] = {"v",
                               "from 0 0 6",
                               "at 0 0 0",
                               "up 0 1 0",
                               "angle 40",
                               "hither 0.01",
                               "resolution 8 8",
                               "b 0 0 0",
                               "l 3 4 6",
                               "f 1 0 0 1 0 1 0 0",
                               "s -1 0 0 0.8 # left",
                               "s 1 0 0 0.8",
                               "s 0 0 0 -1"};
  for (const std::string eol : {"\n", "\r\n", "\r"}) {
    for (const std::string bom : {"", "\xEF\xBB\xBF"}) {
      std::string text = bom;
      for (const std::string& l : lines) text += l + eol;
      const auto errors = Errors(text);
      ASSERT_EQ(errors.size(), 1u) << errors[0];
      // The comment ended at its line end: the sphere after it was read, and the bad
      // radius is reported on line 13, column 1.
      EXPECT_NE(errors[0].find("t.nff:13:1: expected a sphere radius > 0"), std::string::npos)
          << errors[0];
      std::vector<std::string> none;
      const auto scene = ParseNff(text.substr(0, text.rfind("s 0 0 0 -1")), "t.nff", none);
      ASSERT_TRUE(scene) << none[0];
      EXPECT_EQ(scene->objects.size(), 2u);
      EXPECT_EQ(scene->objects[1].where.line, 12);
    }
  }
  // A mark anywhere else is no keyword, and it is shown, not invisible.
  const auto errors = Errors(std::string(kView) + "f 1 1 1 1 0 0 0 1\n\xEF\xBB\xBFs 0 0 0 1\n");
  EXPECT_NE(errors[0].find("unknown keyword '\\xef\\xbb\\xbfs'"), std::string::npos) << errors[0];
}

// Issue 11: a NUL or control byte is escaped in messages, so the whole report is printed.
TEST(SceneNff, BytesThatAreNotPrintableAreEscapedAndEveryErrorIsListed) {
  try {
    ParseNffOrThrow(
        std::string(kView) + "f 1 1 1 1 0 0 0 1\nfoo" + std::string(1, '\0') + "bar\nq\x01\nz\n",
        "x.nff");
    FAIL() << "expected a UserError";
  } catch (const UserError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\0'), std::string::npos);
    EXPECT_NE(m.find("3 errors"), std::string::npos) << m;
    EXPECT_NE(m.find("x.nff:10:1: unknown keyword 'foo\\x00bar'"), std::string::npos) << m;
    EXPECT_NE(m.find("x.nff:11:1: unknown keyword 'q\\x01'"), std::string::npos) << m;
    EXPECT_NE(m.find("x.nff:12:1: unknown keyword 'z'"), std::string::npos) << m;
  }
}

// Issue 11: what the reader cannot hold is a clear error before anything is read.
TEST(SceneNff, DirectoriesDevicesAndHugeFilesAreClearErrors) {
  auto message = [](const std::string& path) {
    try {
      ReadNffFile(path);
    } catch (const UserError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const auto dir =
      std::filesystem::temp_directory_path() / ("zephyr_nff_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  EXPECT_NE(message(dir.string()).find("is a directory"), std::string::npos);
  EXPECT_NE(message("/dev/zero").find("is not a regular file"), std::string::npos);
  EXPECT_NE(message((dir / "none.nff").string()).find("cannot open"), std::string::npos);
  const auto big = dir / "big.nff";
  { std::ofstream(big) << "b 0 0 0\n"; }
  std::filesystem::resize_file(big, kMaxSceneBytes + 1);  // sparse: costs no disk
  EXPECT_NE(message(big.string()).find("more than the 64 MiB"), std::string::npos)
      << message(big.string());
  std::filesystem::resize_file(big, 8);
  EXPECT_NE(message(big.string()).find("missing 'v'"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// Issue 11: every material value is range-checked alike and reported at its own column.
TEST(SceneNff, EveryMaterialValueIsCheckedAgainstItsRangeAtItsColumn) {
  struct Case {
    const char* f;
    const char* want;
  };
  const Case cases[] = {
      {"f 1.5 1 1 1 0 0 0 1", "t.nff:9:3: expected the material's red r from 0 to 1, got '1.5'"},
      {"f 1 -1 1 1 0 0 0 1", "t.nff:9:5: expected the material's green g from 0 to 1"},
      {"f 1 1 2 1 0 0 0 1", "t.nff:9:7: expected the material's blue b from 0 to 1"},
      {"f 1 1 1 1.2 0 0 0 1", "t.nff:9:9: expected the diffuse weight Kd from 0 to 1"},
      {"f 1 1 1 1 -0.1 0 0 1",
       "t.nff:9:11: expected the specular and mirror weight Ks from 0 to 1"},
      {"f 1 1 1 1 0 -3 0 1", "t.nff:9:13: expected the Phong exponent Shine >= 0"},
      {"f 1 1 1 1 0 0 1.5 1", "t.nff:9:15: expected the transmission T from 0 to 1, got '1.5'"},
      {"f 1 1 1 1 0 0 -1 1", "t.nff:9:15: expected the transmission T from 0 to 1"},
      {"f 1 1 1 1 0 0 0 -1", "t.nff:9:17: expected the index of refraction ior >= 0"},
      {"f 1 1 1 1 0 0 0.5 0",
       "t.nff:9:19: expected an index of refraction ior > 0 for a transparent"},
  };
  for (const Case& c : cases) {
    const auto errors = Errors(std::string(kView) + c.f + "\ns 0 0 0 1\n");
    ASSERT_EQ(errors.size(), 1u) << c.f;
    EXPECT_NE(errors[0].find(c.want), std::string::npos) << errors[0];
  }
  std::vector<std::string> errors;  // both ends of each range are allowed
  EXPECT_TRUE(ParseNff(std::string(kView) + "f 0 1 0 1 0 0 1 1.5\nf 1 0 1 0 1 1e5 0 0\ns 0 0 0 1\n",
                       "t.nff", errors));
}

// Issue 11: a bad view is reported at the line of the item that is wrong.
TEST(SceneNff, ViewErrorsPointAtTheirOwnLine) {
  auto view = [](const std::string& from, const std::string& at, const std::string& up) {
    return "b 0 0 0\nv\nfrom " + from + "\nat " + at + "\nup " + up +
           "\nangle 30\nhither 0\nresolution 5 5\nf 1 1 1 1 0 0 0 1\ns 0 0 0 1\n";
  };
  auto one = [](const std::vector<std::string>& e) {
    return e.size() == 1 ? e[0] : std::string("several");
  };
  EXPECT_NE(one(Errors(view("1 2 3", "1 2 3", "0 1 0")))
                .find("t.nff:3:1: the view's 'from' equals 'at' (t.nff:4:1)"),
            std::string::npos);
  EXPECT_NE(one(Errors(view("0 0 5", "0 0 0", "0 0 0"))).find("t.nff:5:1: the view's 'up' is zero"),
            std::string::npos);
  EXPECT_NE(
      one(Errors(view("0 0 5", "0 0 0", "0 0 -2"))).find("t.nff:5:1: the view's 'up' is parallel"),
      std::string::npos);
  // A malformed 'from' or 'up' is its own error only: no second one about the view built
  // from its unread values.
  EXPECT_NE(one(Errors(view("0 0 x", "0 0 0", "0 1 0")))
                .find("t.nff:3:10: expected a number for the eye"),
            std::string::npos);
  EXPECT_NE(
      one(Errors(view("0 0 5", "0 0 0", "0 0 ?"))).find("t.nff:5:8: expected a number for the up"),
      std::string::npos);
  std::vector<std::string> errors;  // huge and tiny vectors are fine: the test is scaled
  EXPECT_TRUE(ParseNff(view("0 0 5", "0 0 0", "0 1e300 0"), "t.nff", errors));
  EXPECT_TRUE(ParseNff(view("0 0 5", "0 0 0", "0 1e-300 0"), "t.nff", errors));
}

// Issue 11: values whose squares overflow double are rejected with their line, per item;
// large values within the limit are read.
TEST(SceneNff, ValuesWhoseSquaresOverflowAreRejectedWithTheirLine) {
  const std::string f = "f 1 1 1 1 0 0 0 1\n";
  auto first = [](const std::vector<std::string>& e) { return e.empty() ? std::string() : e[0]; };
  EXPECT_NE(first(Errors(std::string(kView) + f + "s 0 0 10 1e155\n"))
                .find("t.nff:10:1: sphere reaches 1e+155"),
            std::string::npos);
  EXPECT_NE(first(Errors(std::string(kView) + f + "s 0 0 0 1\ns 1e300 0 0 1\n"))
                .find("t.nff:11:1: sphere reaches"),
            std::string::npos);
  EXPECT_NE(first(Errors(std::string(kView) + f + "s 0 0 0 1\nl 0 0 -1e200\n"))
                .find("t.nff:11:1: light reaches"),
            std::string::npos);
  EXPECT_NE(first(Errors("b 0 0 0\nv\nfrom 0 0 1e160\nat 0 0 0\nup 0 1 0\nangle 30\nhither "
                         "0\nresolution 5 5\n" +
                         f + "s 0 0 0 1\n"))
                .find("t.nff:3:1: the eye ('from') reaches"),
            std::string::npos);
  EXPECT_NE(first(Errors(std::string(kView) + f + "c 0 0 0 1e151 0 0 1e140 1e151\n"))
                .find("t.nff:10:1: cone"),
            std::string::npos);
  // A transform that shrinks a huge sphere to size 1: in its own coordinates the sphere
  // (1e152) and the eye (1e153) lie past 1e150 and their squares overflow, though the
  // world-space sphere is small. The transform itself is regular (not "singular": its plain
  // determinant, 1e-456, underflows, but the test is free of the matrix's scale).
  EXPECT_NE(first(Errors(std::string(kView) + f +
                         "transform 1e-152 0 0 0 0 1e-152 0 0 0 0 1e-152 0\n"
                         "s 0 0 0 1e152\n"))
                .find("t.nff:11:1: sphere (in its own coordinates"),
            std::string::npos);
  // The sphere itself within the limit in its own coordinates (radius 1e148, 1 in the world)
  // but a light 1000 away lies at 1e151 there: what the object meets is checked too.
  EXPECT_NE(first(Errors(std::string(kView) + f +
                         "l 0 0 1000\ntransform 1e-148 0 0 0 0 1e-148 0 0 0 0 1e-148 0\n"
                         "s 0 0 0 1e148\n"))
                .find("t.nff:12:1: sphere (in its own coordinates"),
            std::string::npos);
  std::vector<std::string> errors;
  EXPECT_TRUE(ParseNff(std::string(kView) + f +
                           "l 0 0 1\ntransform 1e-148 0 0 0 0 1e-148 0 0 0 0 1e-148 0\n"
                           "s 0 0 0 1e148\n",
                       "t.nff", errors))
      << first(errors);
  EXPECT_TRUE(ParseNff(
      "b 0 0 0\nv\nfrom 0 0 1e140\nat 0 0 0\nup 0 1 0\nangle 30\nhither 0\nresolution 5 5\n" + f +
          "s 0 0 0 1e139\nl 0 1e140 1e140\n",
      "t.nff", errors))
      << first(errors);
}

// Issue 11: NFF lights without a colour get the SPD readme's √N/(2N) each and an ambient
// term of the same (docs/scene-format.md); given colours are kept, with no ambient term.
TEST(SceneNff, LightsWithoutColourShareSqrtNOver2N) {
  std::vector<std::string> errors;
  auto spd =
      ParseNff(std::string(kView) + "l 1 2 3\nl 4 5 6\nl 7 8 9\nf 1 1 1 1 0 0 0 0\ns 0 0 0 1\n",
               "t.nff", errors);
  ASSERT_TRUE(spd);
  const double each = std::sqrt(3.0) / 6;
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(spd->LightColour(i), (Vec3{each, each, each}));
  EXPECT_DOUBLE_EQ(spd->Ambient(), each);
  EXPECT_NE(WriteNff(*spd).find("l 1 2 3\n"), std::string::npos);  // written back without a colour
  auto one =
      ParseNff(std::string(kView) + "l 1 2 3\nf 1 1 1 1 0 0 0 0\ns 0 0 0 1\n", "t.nff", errors);
  ASSERT_TRUE(one);
  EXPECT_EQ(one->LightColour(0), (Vec3{0.5, 0.5, 0.5}));
  EXPECT_DOUBLE_EQ(one->Ambient(), 0.5);
  auto given = ParseNff(
      std::string(kView) + "l 1 2 3 1 1 1\nl 4 5 6 0.2 0.3 0.4\nf 1 1 1 1 0 0 0 0\ns 0 0 0 1\n",
      "t.nff", errors);
  ASSERT_TRUE(given);
  EXPECT_EQ(given->LightColour(0), (Vec3{1, 1, 1}));
  EXPECT_EQ(given->LightColour(1), (Vec3{0.2, 0.3, 0.4}));
  EXPECT_EQ(given->Ambient(), 0);
}

TEST(SceneNff, WriteThenReadIsExact) {
  for (const Scene& s : {GenerateRandomSpheres({20, 7, 64, 64}), GenerateSphereflake(1),
                         GenerateTransformedShowcase()}) {
    std::vector<std::string> errors;
    auto back = ParseNff(WriteNff(s), "w.nff", errors);
    ASSERT_TRUE(back) << errors[0];
    ASSERT_EQ(back->objects.size(), s.objects.size());
    EXPECT_EQ(WriteNff(*back), WriteNff(s));
  }
}

// The SPD samples the repository ships (balls, jacks, lattice, tetra; the fuzz seed corpus).
TEST(SceneNff, ReadsEverySpdSample) {
  const std::filesystem::path dir = "tests/fuzz/corpus";
  ASSERT_TRUE(std::filesystem::exists(dir)) << "run from the repository's top folder";
  int read = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".nff") continue;
    Scene s = ReadNffFile(entry.path().string());
    EXPECT_GT(s.objects.size(), 0u) << entry.path();
    ++read;
  }
  EXPECT_GE(read, 5);  // 4 SPD samples and the showcase
}

TEST(SceneGen, RandomSpheresAreDeterministicAndLeaveBackground) {
  const Scene a = GenerateRandomSpheres({50, 3, 384, 384});
  const Scene b = GenerateRandomSpheres({50, 3, 384, 384});
  const Scene c = GenerateRandomSpheres({50, 4, 384, 384});
  EXPECT_EQ(WriteNff(a), WriteNff(b));
  EXPECT_NE(WriteNff(a), WriteNff(c));
  ASSERT_EQ(a.objects.size(), 50u);
  int glass = 0, mirror = 0;
  for (const Primitive& p : a.objects) {
    const Material& m = a.materials[p.material];
    glass += m.t > 0;
    mirror += m.ks >= 0.5;
    // Every sphere lies inside the central box, so the image corners are background.
    const auto& s = std::get<Sphere>(p.shape);
    EXPECT_LE(std::abs(s.centre.x) + s.radius, 2.2 + 1e-12);
  }
  EXPECT_GT(glass, 0);
  EXPECT_GT(mirror, 0);
}

TEST(SceneGen, SphereflakeHasNinePowerCounts) {
  EXPECT_EQ(GenerateSphereflake(0).objects.size(), 1u + 1);
  EXPECT_EQ(GenerateSphereflake(1).objects.size(), 1u + 1 + 9);
  EXPECT_EQ(GenerateSphereflake(2).objects.size(), 1u + 1 + 9 + 81);
  // SPD balls: each child has a third of its parent's radius and touches it; six sit on the
  // equator, three at 54.74° above it.
  const Scene s = GenerateSphereflake(1);
  const Sphere& parent = std::get<Sphere>(s.objects[1].shape);
  EXPECT_EQ(parent.radius, 0.5);
  int above = 0;
  for (size_t i = 2; i < s.objects.size(); ++i) {
    const Sphere& c = std::get<Sphere>(s.objects[i].shape);
    EXPECT_NEAR(c.radius, parent.radius / 3, 1e-15) << i;
    EXPECT_NEAR(Length(c.centre - parent.centre), parent.radius + c.radius, 1e-12) << i;
    const double elevation = std::asin((c.centre.z - parent.centre.z) / (parent.radius + c.radius));
    if (std::abs(elevation) < 1e-12) continue;
    EXPECT_NEAR(elevation * 180 / M_PI, 54.7356103172, 1e-6) << i;
    ++above;
  }
  EXPECT_EQ(above, 3);
  EXPECT_THROW(GenerateSphereflake(7), UserError);
}

}  // namespace
}  // namespace zephyr

namespace zephyr {
namespace {

// Issue 23: the reader keeps the first kKeptNffErrors messages, counts the rest and stops
// reading at kMaxNffErrors, so a file of bad lines costs a bounded memory whatever its size.
TEST(SceneNff, ErrorsAreCountedKeptBoundedAndReadingStopsAtTheCap) {
  std::string text = std::string(kView) + "f 1 1 1 1 0 0 0 0\n";
  const int viewLines = 9;
  for (int i = 0; i < 5000; ++i) text += "z\n";
  NffErrors errors;
  EXPECT_FALSE(ParseNff(text, "t.nff", errors).has_value());
  EXPECT_EQ(errors.count, kMaxNffErrors);
  EXPECT_EQ(errors.messages.size(), kKeptNffErrors);
  EXPECT_EQ(errors.stoppedAtLine, viewLines + int(kMaxNffErrors));
  EXPECT_NE(errors.messages.front().find("t.nff:10:1: unknown keyword 'z'"), std::string::npos)
      << errors.messages.front();
  const std::string summary = errors.Summary();
  EXPECT_NE(summary.find("1000 or more errors in scene:"), std::string::npos) << summary;
  EXPECT_NE(summary.find("... and 980 more; reading stopped at line 1009 after 1000 errors"),
            std::string::npos)
      << summary;
  // Below the cap every error is counted and the file is read to its end (the missing view
  // items at the end are reported).
  NffErrors few;
  EXPECT_FALSE(ParseNff("z\nz\nz\n", "t.nff", few).has_value());
  EXPECT_EQ(few.stoppedAtLine, 0);
  EXPECT_EQ(few.count, 3u + 8u);  // three 'z' and the eight missing view items
}

// The 64 MiB file of the issue (a view, then 33 million lines 'z') ends with exit 1 and the
// capped list, under a 1 GiB address-space limit (it reached 6.1 GB and died before).
TEST(SceneNff, A64MiBFileOfBadLinesEndsWithACleanErrorInBoundedMemory) {
  const std::string dir =
      std::filesystem::temp_directory_path() / ("zephyr-nff-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/bad.nff";
  {
    std::ofstream out(path, std::ios::binary);
    out << kView << "f 1 1 1 1 0 0 0 0\n";
    std::string lines;  // 1 MiB of lines "z", written 63 times
    for (size_t i = 0; i < (size_t(1) << 19); ++i) lines += "z\n";
    const size_t room = kMaxSceneBytes - 200;
    for (size_t written = 0; written + lines.size() <= room; written += lines.size()) out << lines;
  }
  ASSERT_GT(std::filesystem::file_size(path), uintmax_t(60) << 20);
  const std::string zephyr =
      (std::filesystem::read_symlink("/proc/self/exe").parent_path() / "zephyr").string();
  FILE* pipe = ::popen(
      ("bash -c 'ulimit -v 1048576; " + zephyr + " render --method seq " + path + "' 2>&1").c_str(),
      "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char buffer[4096];
  while (size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
  const int raw = ::pclose(pipe);
  std::filesystem::remove_all(dir);
  EXPECT_TRUE(WIFEXITED(raw) && WEXITSTATUS(raw) == 1) << raw << "\n" << output;
  EXPECT_NE(output.find("reading stopped at line 1009 after 1000 errors"), std::string::npos)
      << output;
  EXPECT_EQ(output.find("bad_alloc"), std::string::npos) << output;
  EXPECT_LT(output.size(), 4000u);
}

// A file name is printed whole in every message (editors jump to it); tokens are cut.
TEST(SceneNff, FileNamesArePrintedWholeInEveryError) {
  const std::string name =
      "runs/a_very_long_directory_name_for_testing_paths_longer_than_forty/s.nff";
  std::vector<std::string> errors;
  EXPECT_FALSE(
      ParseNff(std::string(kView) + "f 1 1 1 1 0 0 0 0\ns 0 0 0 -1\n" + std::string(60, 'q') + "\n",
               name, errors)
          .has_value());
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[0].rfind(name + ":10:1: expected a sphere radius > 0", 0), 0u) << errors[0];
  EXPECT_EQ(errors[1].rfind(name + ":11:1: unknown keyword '" + std::string(40, 'q') + "...'", 0),
            0u)
      << errors[1];
  try {
    ReadNffFile("/nonexistent/" + name);
    ADD_FAILURE() << "no error";
  } catch (const UserError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("/nonexistent/" + name + ": cannot open", 0), 0u)
        << e.what();
  }
}

// Issue 23, smaller faults: a number that underflows is called so (not "not finite"); a
// file with parse errors still lists its magnitude error; a symbolic-link loop is ELOOP,
// not "no such file".
TEST(SceneNff, UnderflowMagnitudeWithOtherErrorsAndLinkLoopsAreNamedForWhatTheyAre) {
  const std::string f = "f 1 1 1 1 0 0 0 0\n";
  auto under = Errors(std::string(kView) + f + "s 0 0 1e-400 1\n");
  ASSERT_EQ(under.size(), 1u);
  EXPECT_NE(under[0].find("t.nff:10:7: expected a number for the sphere centre"), std::string::npos)
      << under[0];
  EXPECT_NE(under[0].find("'1e-400', which underflows double"), std::string::npos) << under[0];
  auto over = Errors(std::string(kView) + f + "s 0 0 1e400 1\n");
  ASSERT_EQ(over.size(), 1u);
  EXPECT_NE(over[0].find("which overflows double"), std::string::npos) << over[0];
  auto both = Errors(std::string(kView) + f + "s 0 0 0 1e308\nbogus\n");
  ASSERT_EQ(both.size(), 2u);
  EXPECT_NE(both[0].find("t.nff:11:1: unknown keyword 'bogus'"), std::string::npos) << both[0];
  EXPECT_NE(both[1].find("t.nff:10:1: sphere reaches"), std::string::npos) << both[1];
  const std::string dir =
      std::filesystem::temp_directory_path() / ("zephyr-loop-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::filesystem::create_symlink(dir + "/b.nff", dir + "/a.nff");
  std::filesystem::create_symlink(dir + "/a.nff", dir + "/b.nff");
  std::string message;
  try {
    ReadNffFile(dir + "/a.nff");
  } catch (const UserError& e) {
    message = e.what();
  }
  std::filesystem::remove_all(dir);
  EXPECT_NE(message.find("a.nff: cannot open the scene file (Too many levels of symbolic links)"),
            std::string::npos)
      << message;
}

}  // namespace
}  // namespace zephyr

namespace zephyr {
namespace {

// Every number of every statement, when it is not a number or not a finite one, is reported
// at its own line and column: each view item, the background, a light with
// and without colour, the material, a sphere, a cone, a polygon's count and vertices, a `pp`
// normal's components and the 12 entries of a transform.
TEST(SceneNff, EveryNumberOfEveryStatementIsLocatedAtItsOwnColumn) {
  const std::vector<std::string> view = {
      "b 0.1 0.2 0.3", "v",           "from 0 0 10",      "at 0 0 0",         "up 0 1 0",
      "angle 30",      "hither 0.01", "resolution 64 48", "f 1 1 1 1 0 0 0 0"};
  const std::vector<std::string> statements = {"b 0.1 0.2 0.3",
                                               "from 0 0 10",
                                               "at 0 0 0",
                                               "up 0 1 0",
                                               "angle 30",
                                               "hither 0.01",
                                               "resolution 64 48",
                                               "l 1 2 3",
                                               "l 1 2 3 0.5 0.5 0.5",
                                               "f 0.5 0.5 0.5 0.7 0.3 20 0.1 1.5",
                                               "s 1 2 3 0.5",
                                               "c 0 0 0 1 0 0 2 0.5",
                                               "p 3 0 0 0 1 0 0 0 1 0",
                                               "pp 3 0 0 0 0 0 1 1 0 0 0 0 1 0 1 0 0 0 1",
                                               "transform 2 0 0 1 0 2 0 1 0 0 2 1"};
  int checked = 0;
  for (const std::string& statement : statements) {
    std::vector<std::string> tokens;
    for (size_t at = 0; at < statement.size();) {
      const size_t end = std::min(statement.find(' ', at), statement.size());
      tokens.push_back(statement.substr(at, end - at));
      at = end + 1;
    }
    // A view item replaces its own line; anything else is line 10, after the material.
    std::vector<std::string> lines = view;
    int line = 10;
    for (size_t i = 0; i < lines.size(); ++i)
      if (lines[i].substr(0, lines[i].find(' ')) == tokens[0] && tokens[0] != "f")
        line = int(i) + 1;
    if (line == 10) lines.push_back("");
    for (size_t k = 1; k < tokens.size(); ++k) {
      int column = 1;
      for (size_t j = 0; j < k; ++j) column += int(tokens[j].size()) + 1;
      for (const char* bad : {"x", "1e999"}) {
        std::vector<std::string> t = tokens;
        t[k] = bad;
        std::string changed = t[0];
        for (size_t j = 1; j < t.size(); ++j) changed += " " + t[j];
        lines[line - 1] = changed;
        std::string text;
        for (const std::string& l : lines) text += l + "\n";
        text += "s 0 0 0 1\n";  // an object after it, so a statement cut short cannot pass unseen
        std::vector<std::string> errors;
        EXPECT_FALSE(ParseNff(text, "t.nff", errors).has_value()) << changed;
        ASSERT_FALSE(errors.empty()) << changed;
        const std::string where =
            "t.nff:" + std::to_string(line) + ":" + std::to_string(column) + ": ";
        EXPECT_EQ(errors[0].rfind(where, 0), 0u)
            << changed << "\n  expected " << where << "\n  got " << errors[0];
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 2 * (3 + 3 + 3 + 3 + 1 + 1 + 2 + 3 + 6 + 8 + 4 + 8 + 10 + 19 + 12));
}

// A patch's world form under a shear: its vertex normals map by the inverse transpose, so a
// normal perpendicular to the object's surface stays perpendicular to the world's (the
// inverse alone tilts it); its vertices by the map itself, and the Newell normal agrees.
TEST(SceneWorldForm, APatchsNormalsStayPerpendicularUnderAShear) {
  Primitive p;
  const Vec3 up{0, 0, 1};
  p.shape = Polygon{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {up, up, up, up}};
  Affine shear;  // x += 0.5 y + 0.7 z, z += 0.4 x, then a translation
  shear.m[0][1] = 0.5, shear.m[0][2] = 0.7, shear.m[2][0] = 0.4, shear.m[1][3] = 3;
  p.transform = shear;
  const WorldSpacePolygon w = ToWorldSpace(p);
  ASSERT_EQ(w.vertices.size(), 4u);
  ASSERT_EQ(w.normals.size(), 4u);
  EXPECT_EQ(w.vertices[2].x, shear.ApplyPoint({1, 1, 0}).x);
  for (size_t i = 0; i < 4; ++i) {
    const Vec3 edge = w.vertices[(i + 1) % 4] - w.vertices[i];
    EXPECT_NEAR(Dot(w.normals[i], edge), 0, 1e-12) << "vertex " << i;
    EXPECT_NEAR(Dot(Normalize(w.normals[i]), w.normal), 1, 1e-12) << "vertex " << i;
  }
}

}  // namespace
}  // namespace zephyr
