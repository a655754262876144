// Tests for the NFF reader, its error reports and the scene generators.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "fixed/check.h"
#include "hosts/scene/nff.h"
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
      "c 0 0 0 1 0 0 2 0.5\n"        // cone on one line, as SPD jacks writes it
      "c\n1 1 1 0.3\n1 1 3 0.3\n"    // cylinder on two lines
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
  const std::string text = std::string(kView) + "f 1 1 1 1 0 0 0 1\n"
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
  const auto errors = Errors(std::string(kView) + "f 1 1 1 1 0 0 0 1\n"
                             "s 0 0 0 -1\n"       // line 10
                             "  bogus 1 2\n"      // line 11, column 3
                             "s 0 0 nan 1\n"      // line 12, column 7
                             "s 1 1 1 0\n");
  ASSERT_EQ(errors.size(), 4u);
  EXPECT_NE(errors[0].find("t.nff:10:1: expected a sphere radius > 0"), std::string::npos) << errors[0];
  EXPECT_NE(errors[1].find("t.nff:11:3: unknown keyword 'bogus'"), std::string::npos) << errors[1];
  EXPECT_NE(errors[2].find("t.nff:12:7: expected a finite number"), std::string::npos) << errors[2];
  EXPECT_NE(errors[3].find("t.nff:13:1:"), std::string::npos) << errors[3];
}

TEST(SceneNff, RejectsBadScenes) {
  auto has = [](const std::vector<std::string>& errors, const std::string& what) {
    for (const auto& e : errors) if (e.find(what) != std::string::npos) return true;
    return false;
  };
  const std::string f = "f 1 1 1 1 0 0 0 1\n";
  EXPECT_TRUE(has(Errors(f + "s 0 0 0 1\n"), "missing 'v'"));
  EXPECT_TRUE(has(Errors(std::string(kView) + "s 0 0 0 1\n"), "before any material"));
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "s 0 0 1e999 1\n"), "finite number"));
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "s 0 0 inf 1\n"), "finite number"));
  {
    std::vector<std::string> errors;
    auto scene = ParseNff(std::string(kView) + f + "p 3\n0 0 0\n1 1 1\n2 2 2\ns 0 0 0 1\n", "t.nff", errors);
    ASSERT_TRUE(scene);
    EXPECT_EQ(scene->objects.size(), 1u);  // the zero-area polygon is dropped, loudly
    ASSERT_EQ(scene->warnings.size(), 1u);
    EXPECT_NE(scene->warnings[0].find("t.nff:10:1: warning: degenerate polygon"), std::string::npos);
  }
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "p 4\n0 0 0\n1 0 0\n1 1 0.5\n0 1 0\n"), "non-planar"));
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "p 2\n0 0 0\n1 0 0\n"), "integer from 3"));
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "transform 1 0 0 0 2 0 0 0 0 0 0 0\ns 0 0 0 1\n"), "singular transform"));
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "c 0 0 0 1 0 0 0 1\n"), "different points"));
  EXPECT_TRUE(has(Errors(std::string(kView) + f + "s 0 0 0\n"), "unexpected end of file"));
  EXPECT_TRUE(has(Errors("b 0 0 0\nv\nfrom 0 0 1\nat 0 0 0\nup 0 1 0\nangle 30\nhither 0\nresolution 100000 5\n"),
                  "integer from 1 to 16384"));
  EXPECT_TRUE(has(Errors("b 0 0 0\nv\nfrom 0 0 1\nat 0 0 0\nup 0 0 1\nangle 30\nhither 0\nresolution 5 5\n"),
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

TEST(SceneNff, ReadsEverySpdSample) {
  const std::filesystem::path dir = "../shared/scenes";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "no ../shared/scenes in this clone";
  int read = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".nff") continue;
    Scene s = ReadNffFile(entry.path().string());
    EXPECT_GT(s.objects.size(), 0u) << entry.path();
    ++read;
  }
  EXPECT_GE(read, 5);
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
    EXPECT_LE(std::abs(s.center.x) + s.radius, 2.2 + 1e-12);
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
    EXPECT_NEAR(Length(c.center - parent.center), parent.radius + c.radius, 1e-12) << i;
    const double elevation = std::asin((c.center.z - parent.center.z) / (parent.radius + c.radius));
    if (std::abs(elevation) < 1e-12) continue;
    EXPECT_NEAR(elevation * 180 / M_PI, 54.7356103172, 1e-6) << i;
    ++above;
  }
  EXPECT_EQ(above, 3);
  EXPECT_THROW(GenerateSphereflake(7), UserError);
}

}  // namespace
}  // namespace zephyr
