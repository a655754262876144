// The modelled 1992 testbed (docs/testbed.md): counted host work, host profiles, modelled
// seconds of seq and simd (and each charge by closed form on a tiny scene), the platform
// files, and — when `make smpi` built zephyr-smpi — dist and hetero under smpirun: the same
// PNG as seq/simd and the same seconds twice (to the last digit).
#include "hosts/testbed/testbed.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include "bitserial/profile.h"
#include "bitserial/report.h"
#include "fixed/check.h"
#include "hosts/methods/render.h"
#include "hosts/methods/report.h"
#include "hosts/scene/nff.h"
#include "hosts/testbed/host_profile.h"
#include "tests/farm/mpi_launch.h"

namespace zephyr {
namespace {

using testing::ReadFile;
using testing::ReadJson;
using testing::RunCommand;
using testing::RunZephyrProcess;
using testing::TempDir;

std::string WriteScene(const TempDir& dir, int count = 6, const std::string& size = "24x16") {
  std::string path = dir / "s.nff";
  auto r = RunZephyrProcess("gen spheres --count " + std::to_string(count) + " --seed 5 --size " +
                            size + " --out " + path);
  EXPECT_EQ(r.status, 0) << r.output;
  return path;
}

RenderOutput Render(const std::string& scene, const std::string& method, const std::string& bed,
                    const std::string& machine = "") {
  RenderOptions o;
  if (!machine.empty()) o.simd.profile = machine;
  o.method = method;
  o.scenePath = scene;
  o.progress = false;
  o.testbed = bed;
  return RunRender(o);
}

TEST(TestbedWork, SeqCountsEveryPixelAndShadesEveryHit) {
  TempDir dir;
  const RenderOutput out = Render(WriteScene(dir), "seq", "");
  const TraceStats s = *out.hostWork;
  EXPECT_EQ(s.pixels, 24u * 16u);
  EXPECT_EQ(s.rays[int(RayKind::kPrimary)], 24u * 16u);
  EXPECT_EQ(s.shades, s.hits);  // every ray that hits is shaded
  EXPECT_GT(s.hits, 0u);
  EXPECT_GT(s.lightSamples, 0u);
  EXPECT_EQ(TraceStats::FromJson(s.ToJson()).ToJson(), s.ToJson());
}

TEST(TestbedProfile, SecondsAreTheWorkTableAtTheProfilesRates) {
  TraceStats s;
  s.tests[int(ShapeKind::kSphere)] = 1000;
  s.pixels = 10;
  const testbed::HostProfile& ss2 = testbed::HostProfileNamed("sparcstation2");
  const testbed::HostTime t = testbed::ModelHostTime(s, ss2);
  const auto& sphere = testbed::CostOf(testbed::WorkEvent::kSphereTest);
  const auto& pixel = testbed::CostOf(testbed::WorkEvent::kPixel);
  const double expected =
      1000 * sphere.flops / (ss2.mflops.value * 1e6) +
      (1000 * sphere.instructions + 10 * pixel.instructions) / (ss2.mips.value * 1e6);
  EXPECT_DOUBLE_EQ(t.seconds, expected);
  // The same work on the slower SLC takes longer.
  EXPECT_GT(testbed::ModelHostTime(s, testbed::HostProfileNamed("sparcstation-slc")).seconds,
            t.seconds);
  // Every used entry has a source.
  for (const auto& name : testbed::HostProfileNames()) {
    const auto& p = testbed::HostProfileNamed(name);
    EXPECT_FALSE(p.mips.source.empty());
    EXPECT_FALSE(p.mflops.source.empty());
  }
  EXPECT_THROW(testbed::HostProfileNamed("vax780"), UserError);
}

TEST(TestbedModel, SeqReportsModelledSecondsFromItsCounts) {
  TempDir dir;
  const std::string scene = WriteScene(dir);
  const RenderOutput a = Render(scene, "seq", "ufmg1992");
  const RenderOutput b = Render(scene, "seq", "ufmg1992");
  const nlohmann::json t = RenderReportJson(a).at("testbed");
  const double seconds = t.at("modelledSeconds").get<double>();
  EXPECT_GT(seconds, 0);
  EXPECT_EQ(seconds, RenderReportJson(b).at("testbed").at("modelledSeconds").get<double>());
  const testbed::HostTime h =
      testbed::ModelHostTime(*a.hostWork, testbed::HostProfileNamed("sparcstation2"));
  EXPECT_DOUBLE_EQ(seconds, h.seconds);
  EXPECT_EQ(t.at("host").at("events").at("pixel").at("count").get<double>(), 24 * 16);
}

// On every testbed: the array's cycles at its clock, the matrix over the testbed's array link
// (SCSI in 1992, the memory bus of today-pim), the host's shading on the parent's profile.
TEST(TestbedModel, SimdIsArrayPlusItsLinkPlusHostShadingOnEveryTestbed) {
  TempDir dir;
  for (const std::string& bed : testbed::TestbedNames()) {
    SCOPED_TRACE(bed);
    const testbed::Testbed& testbed = testbed::TestbedNamed(bed);
    const RenderOutput out = Render(WriteScene(dir), "simd", bed, testbed.arrayProfile);
    const nlohmann::json t = RenderReportJson(out).at("testbed");
    const nlohmann::json cycles = RenderReportJson(out).at("simd").at("cycles");
    const double clock = cycles.at("clockHz").get<double>();
    EXPECT_EQ(clock, bitserial::Profile(testbed.arrayProfile).clockHz);
    EXPECT_DOUBLE_EQ(t.at("array").at("linkSeconds").get<double>(),
                     cycles.at("byClass").at("host").get<double>() / clock);
    EXPECT_DOUBLE_EQ(
        t.at("array").at("seconds").get<double>() + t.at("array").at("linkSeconds").get<double>(),
        cycles.at("totalCycles").get<double>() / clock);
    EXPECT_DOUBLE_EQ(
        t.at("modelledSeconds").get<double>(),
        cycles.at("totalCycles").get<double>() / clock + t.at("host").at("seconds").get<double>());
    TraceStats hostWork = *out.hostWork;  // the shading and the uncertain pixels' recompute
    hostWork.Add(testbed::RecomputeWork(out.simd->recomputeWork));
    EXPECT_DOUBLE_EQ(
        t.at("host").at("seconds").get<double>(),
        testbed::ModelHostTime(hostWork, testbed::HostProfileNamed(testbed.parentProfile)).seconds);
    EXPECT_GT(t.at("array").at("linkBytes").get<double>(), 0);
    // Two independent sources agree: the bytes the array profile's hostPlane cost moves per
    // second at the array clock are the testbed's link bandwidth (SCSI's 5 MB/s, the memory
    // bus's 25.6 GB/s: docs/testbed.md, docs/present-day.md) — which pins bytes to bits / 8.
    EXPECT_NEAR(
        t.at("array").at("linkBytes").get<double>() / t.at("array").at("linkSeconds").get<double>(),
        t.at("testbed").at("arrayLinkBandwidth").at("value").get<double>(),
        1e-6 * testbed.arrayLinkBandwidth.value);
    // "array active X % of elapsed": the array's own seconds over the modelled time.
    EXPECT_DOUBLE_EQ(
        t.at("arrayActiveShare").get<double>(),
        t.at("array").at("seconds").get<double>() / t.at("modelledSeconds").get<double>());
    EXPECT_GT(t.at("arrayActiveShare").get<double>(), 0);
    EXPECT_LT(t.at("arrayActiveShare").get<double>(), 1);
    EXPECT_EQ(RenderReportJson(out).at("simd").at("cycles").at("virtualPeRatio").get<int>(),
              cycles.at("layers").get<int>());
  }
  // seq runs no array: no share.
  EXPECT_FALSE(RenderReportJson(Render(WriteScene(dir), "seq", "ufmg1992"))
                   .at("testbed")
                   .contains("arrayActiveShare"));
}

// ---- The charges by closed form ---------------------------------------
// Each counted event's modelled seconds by hand on a tiny scene, from the figures the work
// table, the profile and the array publish (`zephyr testbed profiles`, docs/testbed.md,
// docs/bitserial.md), not from the functions that compute them.

// The work table: flops and other instructions per event.
struct PublishedCost {
  const char* event;
  double flops, instructions;
};
constexpr PublishedCost kWorkTable[] = {
    {"sphereTest", 21, 12}, {"coneTest", 70, 25}, {"polygonTest", 44, 30}, {"ray", 25, 20},
    {"hit", 2, 10},         {"shade", 37, 40},    {"lightSample", 66, 40}, {"pixel", 0, 20},
    {"nodeVisit", 2, 12},   {"boxTest", 27, 15},  {"bvhBin", 46, 40},      {"bvhNode", 1176, 600}};
constexpr double kMflops = 4.2, kMips = 28.5;  // sparcstation2, the ufmg1992 host
// The wavetracer array: a 10 MHz clock; one hostPlane (a bit of each of 8192 PEs, 1 KB over
// SCSI) takes 2048 cycles.
constexpr double kArrayClock = 10e6, kPlaneCycles = 2048, kPlaneBytes = 8192 / 8;

double SecondsOf(const char* event, double count) {
  for (const PublishedCost& c : kWorkTable)
    if (std::string(c.event) == event)
      return count * (c.flops / (kMflops * 1e6) + c.instructions / (kMips * 1e6));
  ADD_FAILURE() << "no event " << event;
  return 0;
}

// 3×2 pixels of a floor (Kd 0.5, Ks 0.5: a mirror) under two lights, a sphere and a cone
// hidden below it: every primary ray meets the floor, each hit samples both lights (both
// above: a shadow ray each, which nothing blocks) and sends one reflected ray, which escapes.
// Every ray tests all three objects.
constexpr const char* kTinyScene =
    "v\nfrom 0 1 3\nat 0 0 0\nup 0 1 0\nangle 30\nhither 0\nresolution 3 2\nb 0 0 0\n"
    "l -5 10 5 1 1 1\nl 5 10 5 1 1 1\n"
    "f 1 1 1 0.5 0.5 10 0 0\np 4\n-100 0 -100\n-100 0 100\n100 0 100\n100 0 -100\n"
    "f 1 0 0 1 0 0 0 0\ns 0 -5 0 1\nc 0 -9 0 1 0 -7 0 0.5\n";

std::string WriteTinyScene(const TempDir& dir) {
  const std::string path = dir / "tiny.nff";
  std::ofstream(path) << kTinyScene;
  return path;
}

// A render of the tiny scene (written into dir) by `method` on the ufmg1992 testbed.
RenderOptions TinyRender(const TempDir& dir, const std::string& method) {
  RenderOptions o;
  o.method = method;
  o.scenePath = WriteTinyScene(dir);
  o.progress = false;
  o.testbed = "ufmg1992";
  return o;
}

void ExpectEvents(const nlohmann::json& host, const std::map<std::string, double>& counts,
                  const std::string& what) {
  double seconds = 0;
  for (const auto& [event, count] : counts) {
    const nlohmann::json& e = host.at("events").at(event);
    EXPECT_EQ(e.at("count").get<double>(), count) << what << ": " << event;
    EXPECT_NEAR(e.at("seconds").get<double>(), SecondsOf(event.c_str(), count), 1e-15)
        << what << ": " << event;
    seconds += SecondsOf(event.c_str(), count);
  }
  EXPECT_NEAR(host.at("seconds").get<double>(), seconds, 1e-15) << what;
}

TEST(TestbedClosedForm, SeqChargesEachCountedEventItsPublishedCost) {
  TempDir dir;
  const RenderOutput out = Render(WriteTinyScene(dir), "seq", "ufmg1992");
  // 6 pixels: 6 primary rays, 12 shadow rays (2 lights), 6 reflected: 24 rays, each testing
  // the polygon, the sphere and the cone; 6 hits, 6 shaded points, 12 light samples.
  const std::map<std::string, double> counts = {
      {"sphereTest", 24}, {"coneTest", 24}, {"polygonTest", 24}, {"ray", 24},
      {"hit", 6},         {"shade", 6},     {"lightSample", 12}, {"pixel", 6}};
  const nlohmann::json t = RenderReportJson(out).at("testbed");
  ExpectEvents(t.at("host"), counts, "seq");
  double seconds = 0;
  for (const auto& [event, count] : counts) seconds += SecondsOf(event.c_str(), count);
  EXPECT_NEAR(t.at("modelledSeconds").get<double>(), seconds, 1e-15);
  // 24 · (21/4.2 + 12/28.5) µs for the sphere tests alone, written out once.
  EXPECT_NEAR(t.at("host").at("events").at("sphereTest").at("seconds").get<double>(),
              24 * (21 / 4.2e6 + 12 / 28.5e6), 1e-15);
}

// seq with --accel bvh: the same rays, hits, shades and light samples as the exhaustive
// run, fewer primitive tests, and the hierarchy's node visits, box tests and build, each at
// its published cost (the counts read off the report's "bvh" section).
TEST(TestbedClosedForm, SeqWithTheBvhChargesNodeVisitsBoxTestsAndTheBuild) {
  TempDir dir;
  RenderOptions o = TinyRender(dir, "seq");
  o.trace.accel = Accel::kBvh;
  const RenderOutput out = RunRender(o);
  const nlohmann::json report = RenderReportJson(out);
  const nlohmann::json& bvh = report.at("bvh");
  // Three objects: the root (binned: 3) splits; its children are made too (>= 3 nodes).
  EXPECT_GE(bvh.at("nodesBuilt").get<double>(), 3);
  EXPECT_EQ(bvh.at("binned").get<double>() >= 3, true);
  EXPECT_GT(bvh.at("nodeVisits").get<double>(), 0);
  EXPECT_GT(bvh.at("boxTests").get<double>(), 0);
  std::map<std::string, double> counts = {{"ray", 24},         {"hit", 6},      {"shade", 6},
                                          {"lightSample", 12}, {"pixel", 6},    {"nodeVisit", 0},
                                          {"boxTest", 0},      {"bvhBin", 0},   {"bvhNode", 0},
                                          {"sphereTest", 0},   {"coneTest", 0}, {"polygonTest", 0}};
  counts["nodeVisit"] = bvh.at("nodeVisits").get<double>();
  counts["boxTest"] = bvh.at("boxTests").get<double>();
  counts["bvhBin"] = bvh.at("binned").get<double>();
  counts["bvhNode"] = bvh.at("nodesBuilt").get<double>();
  for (const char* kind : {"sphere", "cone", "polygon"})
    counts[std::string(kind) + "Test"] = report.at("tests").at(kind).get<double>();
  // The sphere and cone lie below the floor, away from every ray: the walk skips them.
  EXPECT_LT(counts["sphereTest"], 24);
  EXPECT_LT(counts["coneTest"], 24);
  const nlohmann::json t = report.at("testbed");
  ExpectEvents(t.at("host"), counts, "seq --accel bvh");
  double seconds = 0;
  for (const auto& [event, count] : counts) seconds += SecondsOf(event.c_str(), count);
  EXPECT_NEAR(t.at("modelledSeconds").get<double>(), seconds, 1e-15);
}

// simd with --accel bvh and every pixel uncertain (--frac-bits 6): the recompute walks the
// hierarchy too, and the testbed prices what it counted (the report's simd.recomputeWork,
// its hits unpriced) on top of the shading's counts; its build is charged once more (the
// recompute's own tracer).
TEST(TestbedClosedForm, SimdWithTheBvhPricesTheRecomputeAsCounted) {
  TempDir dir;
  RenderOptions o = TinyRender(dir, "simd");
  o.simd.formats.fracBits = 6;
  o.simd.uncertain = simd::UncertainPolicy::kRecompute;
  o.trace.accel = Accel::kBvh;
  const nlohmann::json report = RenderReportJson(RunRender(o));
  const nlohmann::json& recompute = report.at("simd").at("recomputeWork");
  ASSERT_EQ(report.at("simd").at("uncertain").at("recomputed").get<double>(), 6);
  EXPECT_EQ(recompute.at("rays").at("primary").get<double>(), 6);
  EXPECT_GT(recompute.at("bvh").at("nodeVisits").get<double>(), 0);
  EXPECT_GT(recompute.at("bvh").at("nodesBuilt").get<double>(), 0);
  // Each recomputed ray meets the floor; the walk skips the sphere and cone below it.
  EXPECT_LT(recompute.at("tests").at("sphere").get<double>(), 6);
  std::map<std::string, double> counts;
  auto both = [&](const char* event, double shading, double recomputed) {
    counts[event] = shading + recomputed;
  };
  uint64_t rays = 0, recomputeRays = 0;
  for (const char* kind : kRayKindNames) {
    rays += report.at("rays").at(kind).get<uint64_t>();
    recomputeRays += recompute.at("rays").at(kind).get<uint64_t>();
  }
  both("ray", double(rays), double(recomputeRays));
  for (const char* kind : {"sphere", "cone", "polygon"})
    both((std::string(kind) + "Test").c_str(), report.at("tests").at(kind).get<double>(),
         recompute.at("tests").at(kind).get<double>());
  both("hit", report.at("hits").get<double>(), 0);  // the recompute's hits are not priced
  both("shade", report.at("shades").get<double>(), 0);
  both("lightSample", report.at("lightSamples").get<double>(), 0);
  both("pixel", report.at("pixels").get<double>(), 0);
  for (const auto& [event, key] : {std::pair{"nodeVisit", "nodeVisits"},
                                   {"boxTest", "boxTests"},
                                   {"bvhBin", "binned"},
                                   {"bvhNode", "nodesBuilt"}})
    both(event, report.at("bvh").at(key).get<double>(), recompute.at("bvh").at(key).get<double>());
  ExpectEvents(report.at("testbed").at("host"), counts, "simd --accel bvh");
}

// The SIMD method: each array pass that ran (the first, and the refine pass when one ran) at
// the array's clock, the host-class cycles as SCSI bytes and seconds, and the host's work:
// shading from the matrix (one test of the hit object per pixel), plus each uncertain pixel
// recomputed — one primary ray and one test of every object.
TEST(TestbedClosedForm, SimdChargesEveryArrayPassTheScsiLinkAndTheHostRecompute) {
  TempDir dir;
  const std::string scene = WriteTinyScene(dir);
  // --frac-bits 6 leaves every pixel uncertain: recomputed (6 each time), or refined on the
  // array first (auto: more than 1 % uncertain).
  for (const std::string uncertain : {"recompute", "auto"}) {
    RenderOptions o;
    o.method = "simd";
    o.scenePath = scene;
    o.progress = false;
    o.testbed = "ufmg1992";
    o.simd.formats.fracBits = 6;
    o.simd.uncertain =
        uncertain == "recompute" ? simd::UncertainPolicy::kRecompute : simd::UncertainPolicy::kAuto;
    const RenderOutput out = RunRender(o);
    const nlohmann::json pass = RenderReportJson(out).at("simd");
    const double n = pass.at("uncertain").at("recomputed").get<double>();
    const bool refined = uncertain == "auto";
    ASSERT_EQ(pass.contains("refine"), refined) << uncertain;
    if (!refined) {
      ASSERT_EQ(n, 6) << "every pixel recomputed";
    }
    // The host: 6 primary rays from the matrix, each refined by one polygon test and a hit,
    // then shaded as seq does (18 secondary rays testing all three objects), and n pixels
    // recomputed: n rays, n tests of each object.
    const std::map<std::string, double> counts = {
        {"sphereTest", 18 + n}, {"coneTest", 18 + n}, {"polygonTest", 6 + 18 + n},
        {"ray", 24 + n},        {"hit", 6},           {"shade", 6},
        {"lightSample", 12},    {"pixel", 6}};
    const nlohmann::json t = RenderReportJson(out).at("testbed");
    ExpectEvents(t.at("host"), counts, uncertain);
    double cycles = 0, hostCycles = 0;
    for (const nlohmann::json* c :
         {&pass.at("cycles"), refined ? &pass.at("refine").at("cycles") : nullptr}) {
      if (!c) continue;
      cycles += c->at("totalCycles").get<double>();
      hostCycles += c->at("byClass").at("host").get<double>();
    }
    const nlohmann::json& array = t.at("array");
    EXPECT_NEAR(array.at("seconds").get<double>(), (cycles - hostCycles) / kArrayClock, 1e-12)
        << uncertain;
    EXPECT_NEAR(array.at("linkSeconds").get<double>(), hostCycles / kArrayClock, 1e-12)
        << uncertain;
    EXPECT_NEAR(array.at("linkBytes").get<double>(), hostCycles / kPlaneCycles * kPlaneBytes, 1e-6)
        << uncertain;
    double host = 0;
    for (const auto& [event, count] : counts) host += SecondsOf(event.c_str(), count);
    EXPECT_NEAR(t.at("modelledSeconds").get<double>(), cycles / kArrayClock + host, 1e-12)
        << uncertain;
  }
}

// The recompute's charge alone, per pixel and per object test: a report with no other work
// and a pass of C cycles (H of them the host class) on scenes of 0..3 spheres, cones and
// polygons, for 0, 1 and 7 recomputed pixels: the modelled seconds are C/clock plus, per
// pixel, one ray and one test of each object.
TEST(TestbedClosedForm, TheHostRecomputeCostsOneRayAndOneTestPerObjectPerPixel) {
  // A pass of 10 hostPlanes (h = 20480 cycles) and 102 976 ALU steps: C = 123 456 cycles.
  const bitserial::MachineProfile profile = bitserial::Profile("wavetracer");
  bitserial::CycleReport pass(&profile, 1);
  bitserial::MicroOpCounts counts;
  counts.Add(bitserial::MicroOp::kHostPlane, 10);
  counts.Add(bitserial::MicroOp::kAluStep, 102976);
  pass.Charge("probe", counts);
  const double c = pass.TotalCycles(), h = pass.ClassCycles(bitserial::CycleClass::kHost);
  ASSERT_EQ(h, 10 * kPlaneCycles);
  ASSERT_EQ(c, 123456);
  for (const int spheres : {0, 1, 3})
    for (const int cones : {0, 2})
      for (const int polygons : {0, 1, 3}) {
        Scene scene;
        auto add = [&](int count, Shape shape) {
          for (int i = 0; i < count; ++i) scene.objects.emplace_back().shape = shape;
        };
        add(spheres, Sphere{});
        add(cones, Cone{});
        add(polygons, Polygon{});
        for (const int pixels : {0, 1, 7}) {
          const TraceStats none;
          const auto modelled = testbed::ModelTime(
              "ufmg1992",
              {.host = &none, .arrayCycles = &pass, .recomputedPixels = uint64_t(pixels)}, scene);
          ASSERT_TRUE(modelled);
          const nlohmann::json report = {{"testbed", modelled->Json()}};
          const std::string what = std::to_string(pixels) + " pixels, " + std::to_string(spheres) +
                                   " spheres, " + std::to_string(cones) + " cones, " +
                                   std::to_string(polygons) + " polygons";
          const double perPixel = SecondsOf("ray", 1) + spheres * SecondsOf("sphereTest", 1) +
                                  cones * SecondsOf("coneTest", 1) +
                                  polygons * SecondsOf("polygonTest", 1);
          const nlohmann::json& t = report.at("testbed");
          EXPECT_NEAR(t.at("modelledSeconds").get<double>(), c / kArrayClock + pixels * perPixel,
                      1e-15)
              << what;
          EXPECT_NEAR(t.at("host").at("seconds").get<double>(), pixels * perPixel, 1e-15) << what;
          EXPECT_EQ(t.at("host").at("events").at("ray").at("count").get<double>(), pixels) << what;
          EXPECT_EQ(t.at("host").at("events").at("sphereTest").at("count").get<double>(),
                    pixels * spheres)
              << what;
          EXPECT_EQ(t.at("host").at("events").at("coneTest").at("count").get<double>(),
                    pixels * cones)
              << what;
          EXPECT_EQ(t.at("host").at("events").at("polygonTest").at("count").get<double>(),
                    pixels * polygons)
              << what;
          EXPECT_EQ(t.at("host").at("events").at("hit").at("count").get<double>(), 0)
              << what << ": no hit charged";
          EXPECT_NEAR(t.at("array").at("linkBytes").get<double>(), h / kPlaneCycles * kPlaneBytes,
                      1e-9)
              << what;
        }
      }
}

TEST(TestbedModel, BadTestbedAndUnsimulatedFarmAreUserErrors) {
  TempDir dir;
  const std::string scene = WriteScene(dir);
  try {
    Render(scene, "seq", "cray1");
    FAIL() << "an unknown testbed must be refused";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("cray1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("ufmg1992"), std::string::npos) << e.what();
  }
  try {
    Render(scene, "seq", scene);  // an existing file: a platform, simulated only
    FAIL() << "--testbed FILE outside SimGrid must be refused";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("simrun.sh --children K --platform " + scene),
              std::string::npos)
        << e.what();
  }
  try {
    const TraceStats none;
    const testbed::FarmTimes farm;
    testbed::ModelTime("ufmg1992", {.host = &none, .farm = &farm}, ReadNffFile(scene));
    FAIL() << "dist with --testbed outside SimGrid must be refused";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("zephyr-smpi"), std::string::npos) << e.what();
  }
}

TEST(TestbedPlatform, OneSharedEthernetOnEveryChildRoute) {
  const std::string xml = testbed::PlatformXml(testbed::TestbedNamed("ufmg1992"), 3);
  EXPECT_NE(xml.find("sharing_policy=\"SHARED\""), std::string::npos);
  for (const char* host : {"\"parent\"", "\"zephyr\"", "\"child-1\"", "\"child-3\""})
    EXPECT_NE(xml.find(std::string("id=") + host), std::string::npos) << host;
  EXPECT_EQ(xml.find("\"child-4\""), std::string::npos);
  size_t routes = 0;
  for (size_t at = xml.find("<link_ctn id=\"ethernet\""); at != std::string::npos;
       at = xml.find("<link_ctn id=\"ethernet\"", at + 1))
    ++routes;
  EXPECT_EQ(routes, 3u);
  EXPECT_EQ(testbed::Hostfile(2), "parent\nchild-1\nchild-2\n");
  EXPECT_THROW(testbed::PlatformXml(testbed::TestbedNamed("ufmg1992"), 0), UserError);
}

// --also-testbed: one render priced on more testbeds that share its array gives each the
// seconds a render on that testbed alone gives (the counts do not depend on the testbed); a
// farmed method, a testbed without a first one, or another array are refused before any work.
TEST(TestbedModel, AlsoTestbedPricesTheSameCountsAsARenderOnIt) {
  TempDir dir;
  const std::string scene = WriteScene(dir);
  for (const char* method : {"seq", "simd"}) {
    RenderOptions o;
    o.method = method;
    o.scenePath = scene;
    o.progress = false;
    o.testbed = "ufmg1992";
    o.alsoTestbeds = {"today-zephyr"};
    const RenderOutput both = RunRender(o);
    ASSERT_EQ(both.alsoTestbeds.size(), 1u);
    const RenderOutput alone = Render(scene, method, "today-zephyr");
    EXPECT_EQ(both.alsoTestbeds[0].modelledSeconds, alone.testbed->modelledSeconds) << method;
    EXPECT_EQ(both.testbed->modelledSeconds,
              Render(scene, method, "ufmg1992").testbed->modelledSeconds)
        << method;
    EXPECT_EQ(RenderReportJson(both).at("alsoTestbeds").at(0).at("testbed").at("name"),
              "today-zephyr");
  }
  for (const auto& [flags, message] :
       {std::pair{"--method dist --testbed ufmg1992 --also-testbed today-zephyr",
                  "one testbed a run"},
        std::pair{"--method seq --also-testbed today-zephyr", "need a first one"},
        std::pair{"--method simd --testbed ufmg1992 --also-testbed today-pim",
                  "has the array 'pim-bitsimd-v-bank'"},
        std::pair{"--method seq --testbed ufmg1992 --also-testbed today-zephyr --also-testbed "
                  "today-zephyr",
                  "named twice"},
        std::pair{"--method seq --testbed ufmg1992 --also-testbed ufmg1992", "named twice"},
        std::pair{"--method hetero --testbed today-pim", "tools/testbed/simrun.sh"}}) {
    const auto r = RunZephyrProcess(std::string("render --no-progress ") + flags + " " + scene +
                                    " --out " + (dir / "x.png"));
    EXPECT_NE(r.status, 0) << flags;
    EXPECT_NE(r.output.find(message), std::string::npos) << flags << "\n" << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "x.png")) << flags;
  }
}

// Present-day testbeds: each host its own switch port, "ethernet" the parent's (which every
// child's route crosses) and "ethernet-child-I" each child's, each half the one-way latency;
// the array on its own link (the memory bus for today-pim).
TEST(TestbedPlatform, SwitchedEthernetGivesEveryHostAPort) {
  const testbed::Testbed& bed = testbed::TestbedNamed("today-pim");
  ASSERT_EQ(bed.ethernetTopology, testbed::EthernetTopology::kSwitched);
  const std::string xml = testbed::PlatformXml(bed, 3);
  const std::string half = std::to_string(bed.ethernetLatency.value / 2) + "s";
  for (const char* link : {"ethernet", "ethernet-child-1", "ethernet-child-3"})
    EXPECT_NE(
        xml.find(std::string("<link id=\"") + link + "\" bandwidth=\"" +
                 std::to_string(bed.ethernetBandwidth.value) + "bps\" latency=\"" + half + "\""),
        std::string::npos)
        << link << "\n"
        << xml;
  EXPECT_EQ(xml.find("ethernet-child-4"), std::string::npos);
  EXPECT_NE(xml.find("<route src=\"parent\" dst=\"child-2\"><link_ctn id=\"ethernet\"/>"
                     "<link_ctn id=\"ethernet-child-2\"/></route>"),
            std::string::npos)
      << xml;
  EXPECT_NE(xml.find("<link id=\"memory-bus\" bandwidth=\"" +
                     std::to_string(bed.arrayLinkBandwidth.value) + "Bps\""),
            std::string::npos);
  EXPECT_NE(xml.find("<route src=\"parent\" dst=\"zephyr\"><link_ctn id=\"memory-bus\"/>"),
            std::string::npos);
  // The array host computes at the PIM array's DDR4 command clock.
  EXPECT_NE(xml.find("<host id=\"zephyr\" speed=\"" +
                     std::to_string(bitserial::Profile(bed.arrayProfile).clockHz) + "f\">"),
            std::string::npos);
  // Every entry of every testbed has a source.
  for (const std::string& name : testbed::TestbedNames()) {
    const testbed::Testbed& t = testbed::TestbedNamed(name);
    for (const testbed::Sourced* e :
         {&t.ethernetBandwidth, &t.ethernetLatency, &t.arrayLinkBandwidth})
      EXPECT_FALSE(e->source.empty()) << name;
    EXPECT_FALSE(t.ethernetTopologySource.empty()) << name;
    EXPECT_NO_THROW(testbed::HostProfileNamed(t.parentProfile)) << name;
    EXPECT_NO_THROW(testbed::HostProfileNamed(t.childProfile)) << name;
    EXPECT_NO_THROW(bitserial::Profile(t.arrayProfile)) << name;
  }
}

// `render --testbed NAME` runs the array of that testbed unless --machine names one, which must
// then be the testbed's.
TEST(TestbedModel, ARenderOnATestbedRunsItsArray) {
  TempDir dir;
  const std::string scene = WriteScene(dir), report = dir / "r.json";
  auto r = RunZephyrProcess("render --no-progress --method simd " + scene +
                            " --testbed today-pim --report " + report);
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json j = ReadJson(report);
  EXPECT_EQ(j.at("testbed").at("array").at("profile").get<std::string>(), "pim-bitsimd-v-bank");
  EXPECT_EQ(j.at("testbed").at("hostProfile").at("name").get<std::string>(), "today-calibrated");
  r = RunZephyrProcess("render --no-progress --method simd " + scene +
                       " --testbed today-pim --machine wavetracer --report " + report);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("its array is 'pim-bitsimd-v-bank', but the machine profile is "
                          "'wavetracer'"),
            std::string::npos)
      << r.output;
}

std::string Repo() {  // the checkout: $(BUILD)/bin/zephyr_tests -> ../../
  return std::filesystem::read_symlink("/proc/self/exe")
      .parent_path()
      .parent_path()
      .parent_path()
      .string();
}

TEST(TestbedPlatform, TheCommittedPlatformIsWhatTheProfilesGive) {
  // hosts/testbed/platforms/ufmg1992.xml is data in the repo; it must not drift from the
  // profiles it is written from (`zephyr testbed platform --children 8`).
  EXPECT_EQ(ReadFile(Repo() + "/hosts/testbed/platforms/ufmg1992.xml"),
            testbed::PlatformXml(testbed::TestbedNamed("ufmg1992"), 8));
  EXPECT_EQ(ReadFile(Repo() + "/hosts/testbed/platforms/ufmg1992.hosts"), testbed::Hostfile(8));
}

// ---- Under SimGrid (skipped when `make smpi` has not built zephyr-smpi) -------------------

std::string SmpiPath() {
  return (std::filesystem::read_symlink("/proc/self/exe").parent_path() / "zephyr-smpi").string();
}

TEST(TestbedSimulated, DistAndHeteroMatchSeqAndSimdAndRepeatToTheLastDigit) {
  if (!std::filesystem::exists(SmpiPath())) GTEST_SKIP() << "no zephyr-smpi (make smpi)";
  TempDir dir;
  const std::string scene = WriteScene(dir, 8, "64x64");
  auto single = [&](const std::string& method) {
    std::string out = dir / (method + ".png");
    auto r =
        RunZephyrProcess("render --no-progress --method " + method + " " + scene + " --out " + out);
    EXPECT_EQ(r.status, 0) << r.output;
    return ReadFile(out);
  };
  const std::string seq = single("seq"), simd = single("simd");
  for (const auto& [method, reference] : {std::pair{"dist", &seq}, std::pair{"hetero", &simd}}) {
    double seconds[2];
    for (int run = 0; run < 2; ++run) {
      const std::string out = dir / (std::string(method) + std::to_string(run) + ".png");
      const std::string report = dir / (std::string(method) + std::to_string(run) + ".json");
      auto r = RunCommand("timeout -k 5 300 bash " + Repo() +
                          "/tools/testbed/simrun.sh --children 2 --zephyr " + SmpiPath() +
                          " -- render --no-progress --method " + method + " " + scene +
                          " --frame 32 --testbed ufmg1992 --out " + out + " --report " + report);
      ASSERT_EQ(r.status, 0) << r.output;
      EXPECT_EQ(ReadFile(out), *reference) << method;
      const nlohmann::json j = ReadJson(report);
      seconds[run] = j.at("testbed").at("modelledSeconds").get<double>();
      EXPECT_GT(seconds[run], 0);
      for (const auto& child : j.at("distributed").at("perChild"))
        EXPECT_GT(child.at("work").at("testbed").at("busySeconds").get<double>(), 0) << r.output;
      // What the simulation measured: each child's busy + idle is the modelled time, the
      // parent charged its own work, the Ethernet carried the farm's messages and (hetero)
      // the SCSI link the matrix.
      const nlohmann::json& t = j.at("testbed");
      ASSERT_EQ(t.at("children").size(), 2u);
      for (const auto& child : t.at("children")) {
        EXPECT_GT(child.at("busySeconds").get<double>(), 0);
        EXPECT_GT(child.at("idleSeconds").get<double>(), 0);
        EXPECT_DOUBLE_EQ(
            child.at("busySeconds").get<double>() + child.at("idleSeconds").get<double>(),
            seconds[run]);
      }
      EXPECT_GT(t.at("parent").at("hostWorkSeconds").get<double>(), 0);
      // hetero's array is the parent's pass; dist has none.
      EXPECT_EQ(t.contains("arrayActiveShare"), std::string(method) == "hetero") << t.dump(2);
      if (t.contains("arrayActiveShare")) {
        EXPECT_DOUBLE_EQ(t.at("arrayActiveShare").get<double>(),
                         t.at("parent").at("arrayPassSeconds").get<double>() / seconds[run]);
      }
      std::map<std::string, double> bytes;
      for (const auto& link : t.at("links"))
        bytes[link.at("link")] = link.at("bytes").get<double>();
      const auto& traffic = j.at("distributed").at("traffic");
      const double farmBytes =
          traffic.at("parentToChildren").at("total").at("payloadBytes").get<double>() +
          traffic.at("childrenToParent").at("total").at("payloadBytes").get<double>();
      EXPECT_GE(bytes["ethernet"], farmBytes) << t.dump(2);
      EXPECT_EQ(bytes["scsi"] > 0, std::string(method) == "hetero") << t.dump(2);
    }
    // To the last digit: under SimGrid the farm's clock is the simulated one
    // (hosts/farm/common.h), so no wall-clock time reaches a message or a decision.
    EXPECT_EQ(seconds[0], seconds[1]) << method;
  }
}

// `make charts TESTBED=ufmg1992 QUICK=1` (tools/testbed/charts.sh) end to end: every figure
// in modelled seconds, no cell missing; the winner of each grid point is the fastest of the
// four; dist's children process every pixel of the image.
// A CSV file's rows, each split at its commas (no quoting: the charts' files have none).
std::vector<std::vector<std::string>> CsvRows(const std::string& file) {
  std::ifstream f(file);
  EXPECT_TRUE(f) << file;
  std::vector<std::vector<std::string>> table;
  for (std::string line; std::getline(f, line);) {
    std::vector<std::string> cells;
    std::stringstream in(line);
    for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
    table.push_back(cells);
  }
  return table;
}

bool IsPng(const std::string& file) {
  std::ifstream png(file, std::ios::binary);
  char magic[4] = {};
  png.read(magic, 4);
  return std::string(magic + 1, 3) == "PNG";
}

TEST(TestbedCharts, QuickRunDrawsEveryFigureInModelledSeconds) {
  if (!std::filesystem::exists(SmpiPath())) GTEST_SKIP() << "no zephyr-smpi (make smpi)";
  TempDir dir;
  const std::string out = dir / "charts";
  const std::string bin = std::filesystem::path(SmpiPath()).parent_path().string();
  auto r = RunCommand("QUICK=1 TESTBED=ufmg1992 OUT=" + out + " ZEPHYR=" + bin +
                      "/zephyr ZEPHYR_SMPI=" + SmpiPath() + " timeout -k 5 600 bash " + Repo() +
                      "/tools/testbed/charts.sh");
  ASSERT_EQ(r.status, 0) << r.output;
  auto rows = [&](const std::string& name) { return CsvRows(out + "/" + name + ".csv"); };
  for (const char* name :
       {"fig05_seq_vs_simd", "fig06_seq_vs_dist", "fig07_hetero_vs_dist_2children",
        "fig10_data_flow", "fig11_pixels", "fig12_all_methods", "past_efficiency", "past_ethernet",
        "past_parent", "past_time", "where_each_wins", "array_utilisation"}) {
    const auto table = rows(name);
    ASSERT_GE(table.size(), 3u) << name;  // a header and 2 points at least
    for (size_t i = 1; i < table.size(); ++i)
      for (size_t c = 1; c < table[i].size(); ++c) {
        ASSERT_NE(table[i][c], "NaN") << name << " row " << i << " column " << c;
        EXPECT_GE(std::stod(table[i][c]), 0) << name << " row " << i << " column " << c;
      }
    EXPECT_TRUE(IsPng(out + "/" + std::string(name) + ".png")) << name;
  }
  for (const auto& row : rows("fig11_pixels")) {
    if (row[0] == "frame") continue;                  // the header
    EXPECT_EQ(std::stod(row[1]), 64 * 64) << row[0];  // dist: every pixel
  }
  for (const auto& row : rows("where_each_wins")) {
    if (row[0] == "ethernet_bps")
      continue;  // ethernet_bps,objects,winner,seq_s,simd_s,dist_s,hetero_s,array_s
    ASSERT_EQ(row.size(), 8u);
    int fastest = 1;
    for (int m = 2; m <= 5; ++m)
      if (std::stod(row[2 + m]) < std::stod(row[2 + fastest])) fastest = m;
    EXPECT_EQ(std::stoi(row[2]), fastest) << row[0] << " bit/s, " << row[1] << " objects";
  }
}

// `make future` (tools/testbed/future.sh) in its quick form: on every testbed a crossover chart
// of every method exhaustive and with the BVH and a where-each-wins map with the BVH, each a
// CSV without holes and a PNG; the two testbeds that share the Zephyr priced from one render
// (the same array seconds, their hosts' own); the winners the least of their rows.
TEST(TestbedFuture, QuickRunChartsEveryTestbedExhaustiveAndWithTheBvh) {
  if (!std::filesystem::exists(SmpiPath())) GTEST_SKIP() << "no zephyr-smpi (make smpi)";
  TempDir dir;
  const std::string out = dir / "future";
  const std::string bin = std::filesystem::path(SmpiPath()).parent_path().string();
  auto r =
      RunCommand("QUICK=1 OUT=" + out + " ZEPHYR=" + bin + "/zephyr ZEPHYR_SMPI=" + SmpiPath() +
                 " timeout -k 5 600 bash " + Repo() + "/tools/testbed/future.sh");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const std::string& bed : testbed::TestbedNames()) {
    const auto crossover = CsvRows(out + "/crossover_" + bed + ".csv");
    ASSERT_EQ(crossover.size(), 3u) << bed;  // a header and 8, 32 objects
    ASSERT_EQ(crossover[0].size(), 10u) << bed;
    for (size_t i = 1; i < crossover.size(); ++i)
      for (size_t c = 1; c < crossover[i].size(); ++c) {
        ASSERT_NE(crossover[i][c], "NaN") << bed << " row " << i << " " << crossover[0][c];
        EXPECT_GT(std::stod(crossover[i][c]), 0) << bed << " " << crossover[0][c];
      }
    for (const std::string name : {"crossover_", "wins_bvh_"})
      EXPECT_TRUE(IsPng(out + "/" + name + bed + ".png")) << name << bed;
    for (const auto& row : CsvRows(out + "/wins_bvh_" + bed + ".csv")) {
      if (row[0] == "ethernet_bps") continue;  // the header
      ASSERT_EQ(row.size(), 8u) << bed;
      int fastest = 1;
      for (int m = 2; m <= 5; ++m)
        if (std::stod(row[2 + m]) < std::stod(row[2 + fastest])) fastest = m;
      EXPECT_EQ(std::stoi(row[2]), fastest) << bed << " " << row[0] << " bit/s, " << row[1];
    }
  }
  // runs.csv: testbed,method,accel,objects,children,frame,ethernet_bps,model_s,array_s,host_s.
  std::map<std::string, std::vector<std::string>> runs;
  for (const auto& row : CsvRows(out + "/runs.csv"))
    runs[row[0] + " " + row[1] + " " + row[2] + " " + row[3] + " " + row[4] + " " + row[6]] = row;
  for (const char* method : {"simd", "array"}) {
    const auto& then = runs.at(std::string("ufmg1992 ") + method + " bvh 32 0 0");
    const auto& now = runs.at(std::string("today-zephyr ") + method + " bvh 32 0 0");
    EXPECT_EQ(then[8], now[8]) << method;  // the same Zephyr, the same cycles and SCSI
    EXPECT_GT(std::stod(then[9]), 100 * std::stod(now[9])) << method;  // SPARC vs today's core
  }
  // The hierarchy pays on the host even at 32 spheres: fewer tests, fewer modelled seconds.
  EXPECT_LT(std::stod(runs.at("ufmg1992 seq bvh 32 0 0")[7]),
            std::stod(runs.at("ufmg1992 seq none 32 0 0")[7]));
  EXPECT_EQ(CsvRows(out + "/summary.csv").size(), 1 + testbed::TestbedNames().size() * 2 * 2);
}

// seq and simd on a platform file (`simrun.sh --children 0`): on the paper's platform the
// same seconds as the named testbed; on a user's platform whose host is an SLC, the SLC
// profile's seconds for the same counts.
TEST(TestbedSimulated, SeqAndSimdOnAPlatformFile) {
  if (!std::filesystem::exists(SmpiPath())) GTEST_SKIP() << "no zephyr-smpi (make smpi)";
  TempDir dir;
  const std::string scene = WriteScene(dir, 8, "64x64");
  auto simulated = [&](const std::string& method, const std::string& platform) {
    const std::string report = dir / (method + ".json");
    auto r = RunCommand(
        "timeout -k 5 300 bash " + Repo() + "/tools/testbed/simrun.sh --children 0 " +
        (platform.empty() ? "" : "--platform " + platform + " ") + "--zephyr " + SmpiPath() +
        " -- render --no-progress --method " + method + " " + scene + " --testbed ufmg1992 --out " +
        (dir / (method + ".png")) + " --report " + report);
    EXPECT_EQ(r.status, 0) << r.output;
    return ReadJson(report);
  };
  for (const char* method : {"seq", "simd"}) {
    const nlohmann::json t = RenderReportJson(Render(scene, method, "ufmg1992")).at("testbed");
    // Under SimGrid the matrix crosses the SCSI link with the network model's 5 % cross
    // traffic (docs/testbed.md, "Bytes on the Ethernet"): 1.05 times the SCSI seconds.
    const double named =
        t.at("modelledSeconds").get<double>() +
        (t.contains("array") ? 0.05 * t.at("array").at("linkSeconds").get<double>() : 0.0);
    const nlohmann::json j = simulated(method, "");
    EXPECT_NEAR(j.at("testbed").at("modelledSeconds").get<double>(), named, 1e-9 * named) << method;
    EXPECT_EQ(j.at("testbed").at("hostProfile").at("profile"), "sparcstation2")
        << j.at("testbed").dump(2);
  }
  // A user's platform: the host/parent is an SLC (its profile named; the speed only converts).
  std::string xml = ReadFile(Repo() + "/hosts/testbed/platforms/ufmg1992.xml");
  const std::string from =
      "<host id=\"parent\" speed=\"4200000.000000f\">\n      <prop id=\"zephyr:profile\" "
      "value=\"sparcstation2\"/>";
  ASSERT_NE(xml.find(from), std::string::npos);
  xml.replace(xml.find(from), from.size(),
              "<host id=\"parent\" speed=\"1200000f\">\n      <prop id=\"zephyr:profile\" "
              "value=\"sparcstation-slc\"/>");
  const std::string platform = dir / "slc.xml";
  std::ofstream(platform) << xml;
  const nlohmann::json j = simulated("seq", platform);
  const double slc =
      testbed::ModelHostTime(TraceStats::FromJson(j), testbed::HostProfileNamed("sparcstation-slc"))
          .seconds;
  EXPECT_NEAR(j.at("testbed").at("modelledSeconds").get<double>(), slc, 1e-9 * slc);
}

// The refine pass is charged under SimGrid as well: simd on the tiny scene at --frac-bits 6
// (every pixel uncertain, so auto refines them on the array) on the paper's platform takes
// the named testbed's seconds, both passes' cycles included (the SCSI transfer 1.05 times as
// long, as above).
TEST(TestbedSimulated, SimdChargesItsRefinePassOnThePlatform) {
  if (!std::filesystem::exists(SmpiPath())) GTEST_SKIP() << "no zephyr-smpi (make smpi)";
  TempDir dir;
  const std::string scene = WriteTinyScene(dir);
  RenderOptions o;
  o.method = "simd";
  o.scenePath = scene;
  o.progress = false;
  o.testbed = "ufmg1992";
  o.simd.formats.fracBits = 6;
  o.simd.uncertain = simd::UncertainPolicy::kAuto;  // the command line's default
  const nlohmann::json named = RenderReportJson(RunRender(o));
  ASSERT_TRUE(named.at("simd").contains("refine"));
  const nlohmann::json& t = named.at("testbed");
  const double expected =
      t.at("modelledSeconds").get<double>() + 0.05 * t.at("array").at("linkSeconds").get<double>();
  const std::string report = dir / "r.json";
  auto r = RunCommand(
      "timeout -k 5 300 bash " + Repo() + "/tools/testbed/simrun.sh --children 0 --zephyr " +
      SmpiPath() + " -- render --no-progress --method simd " + scene +
      " --frac-bits 6 --testbed ufmg1992 --out " + (dir / "s.png") + " --report " + report);
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json j = ReadJson(report);
  ASSERT_TRUE(j.at("simd").contains("refine"));
  EXPECT_NEAR(j.at("testbed").at("modelledSeconds").get<double>(), expected, 1e-9 * expected)
      << j.at("testbed").dump(2);
}

// `testbed calibrate` reads only a report it can trust (issue 39): `[]` aborted; negative
// counts (nlohmann wrapped them to 2^64 - n) and a render of 1e-300 s were calibrated from.
TEST(TestbedSimulated, CalibrateRefusesAReportItCannotTrust) {
  TempDir dir;
  const std::string scene = WriteScene(dir, 8, "32x32");
  const std::string measured = dir / "m.json";
  ASSERT_EQ(
      RunZephyrProcess("render --no-progress --method seq " + scene + " --report " + measured)
          .status,
      0);
  const nlohmann::json good = ReadJson(measured);
  auto refused = [&](const nlohmann::json& report, const std::string& want) {
    const std::string file = dir / "bad.json";
    std::ofstream(file) << report.dump();
    const auto r = RunZephyrProcess("testbed calibrate --report " + file);
    EXPECT_NE(r.status, 0) << report.dump().substr(0, 200);
    EXPECT_NE(r.output.find(want), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("internal check"), std::string::npos) << r.output;
  };
  refused(nlohmann::json::array(), "expected a render report (a JSON object), got array");
  nlohmann::json negative = good;
  negative["tests"]["sphere"] = -5;
  refused(negative, "counted work: tests.sphere must be a whole number from 0, got -5");
  nlohmann::json fraction = good;
  fraction["hits"] = 2.5;
  refused(fraction, "counted work: hits must be a whole number from 0, got 2.5");
  nlohmann::json instant = good;
  instant["phases"]["render"] = 1e-300;
  refused(instant, "phases.render must be a time from 1e-6 s");
  {
    // A good report followed by a NUL and anything: nlohmann would stop at the NUL.
    const std::string file = dir / "nul.json";
    std::ofstream(file, std::ios::binary) << good.dump() << '\0' << "{\"hits\": -1}";
    const auto r = RunZephyrProcess("testbed calibrate --report " + file);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find(file + ":1:" + std::to_string(good.dump().size() + 1) +
                            ": a NUL byte (a text file holds none)"),
              std::string::npos)
        << r.output;
  }
  const auto fifo = RunZephyrProcess("testbed calibrate --report /dev/null");
  EXPECT_NE(fifo.status, 0);
  EXPECT_NE(fifo.output.find("/dev/null: is not a regular file"), std::string::npos) << fifo.output;
}

// this-host: `zephyr testbed calibrate` turns a measured seq render into operations per
// second; a platform of that speed (`testbed platform --host-ops`) models the same render in
// the seconds it was measured in. Reports of another method, or not JSON, are refused by name.
TEST(TestbedSimulated, ThisHostCalibratedModelsItsOwnRender) {
  TempDir dir;
  const std::string scene = WriteScene(dir, 8, "64x64");
  const std::string measured = dir / "m.json";
  auto r = RunZephyrProcess("render --no-progress --method seq " + scene + " --report " + measured);
  ASSERT_EQ(r.status, 0) << r.output;
  r = RunZephyrProcess("testbed calibrate --report " + measured);
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json c = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  const double seconds = ReadJson(measured).at("phases").at("render").get<double>();
  EXPECT_EQ(c.at("measuredSeconds").get<double>(), seconds);
  const double ops = c.at("operationsPerSecond").get<double>();
  EXPECT_DOUBLE_EQ(ops * seconds, c.at("flops").get<double>() + c.at("instructions").get<double>());
  const std::string simd = dir / "simd.json";
  ASSERT_EQ(
      RunZephyrProcess("render --no-progress --method simd " + scene + " --report " + simd).status,
      0);
  r = RunZephyrProcess("testbed calibrate --report " + simd);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find(simd), std::string::npos) << r.output;
  r = RunZephyrProcess("testbed calibrate --report " + scene);  // not JSON
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find(scene), std::string::npos) << r.output;

  if (!std::filesystem::exists(SmpiPath())) GTEST_SKIP() << "no zephyr-smpi (make smpi)";
  const std::string platform = dir / "this-host.xml";
  r = RunZephyrProcess("testbed platform --children 1 --host-ops " + std::to_string(ops) +
                       " --out " + platform);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(ReadFile(platform).find("zephyr:profile"), std::string::npos);
  const std::string report = dir / "sim.json";
  r = RunCommand("timeout -k 5 300 bash " + Repo() +
                 "/tools/testbed/simrun.sh --children 0 --platform " + platform + " --zephyr " +
                 SmpiPath() + " -- render --no-progress --method seq " + scene +
                 " --testbed ufmg1992 --out " + (dir / "sim.png") + " --report " + report);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NEAR(ReadJson(report).at("testbed").at("modelledSeconds").get<double>(), seconds,
              1e-6 * seconds);
}

// Under SimGrid the platform must be the testbed the render names, and its array the machine
// profile the pass runs: a mismatch is refused, not priced on the wrong machines.
TEST(TestbedSimulated, APlatformOfAnotherTestbedOrArrayIsRefused) {
  if (!std::filesystem::exists(SmpiPath())) GTEST_SKIP() << "no zephyr-smpi (make smpi)";
  TempDir dir;
  const std::string scene = WriteScene(dir, 8, "32x32"), report = dir / "r.json";
  auto r = RunCommand("timeout -k 5 300 bash " + Repo() + "/tools/testbed/simrun.sh --children 2 " +
                      "--zephyr " + SmpiPath() + " -- render --no-progress --method dist " + scene +
                      " --frame 16 --testbed today-pim --report " + report);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("the simulated platform is testbed 'ufmg1992''s"), std::string::npos)
      << r.output;
  const std::string platform = dir / "p.xml";
  ASSERT_EQ(RunZephyrProcess("testbed platform --testbed today-pim --children 1 --out " + platform)
                .status,
            0);
  r = RunCommand("timeout -k 5 300 bash " + Repo() + "/tools/testbed/simrun.sh --children 0 " +
                 "--platform " + platform + " --zephyr " + SmpiPath() +
                 " -- render --no-progress --method simd " + scene + " --testbed " + platform +
                 " --report " + report);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("the simulated platform's array is 'pim-bitsimd-v-bank', but the "
                          "machine profile is 'wavetracer'"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(report));
}

TEST(TestbedSimulated, TooFewHostsNamesTheFile) {
  if (!std::filesystem::exists(SmpiPath())) GTEST_SKIP() << "no zephyr-smpi (make smpi)";
  TempDir dir;
  const std::string platform = dir / "p.xml";
  auto r = RunZephyrProcess("testbed platform --children 1 --out " + platform);
  ASSERT_EQ(r.status, 0) << r.output;
  r = RunCommand("bash " + Repo() + "/tools/testbed/simrun.sh --children 3 --platform " + platform +
                 " --zephyr " + SmpiPath() + " -- render --method dist x.nff");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find(platform), std::string::npos) << r.output;
  // --testbed FILE is the same as --platform FILE.
  r = RunCommand("bash " + Repo() + "/tools/testbed/simrun.sh --children 3 --testbed " + platform +
                 " --zephyr " + SmpiPath() + " -- render --method dist x.nff");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find(platform), std::string::npos) << r.output;
  // A testbed name simrun does not know is the program's refusal, before SimGrid starts.
  r = RunCommand("bash " + Repo() + "/tools/testbed/simrun.sh --children 1 --testbed nosuch" +
                 " --zephyr " + SmpiPath() + " -- render --method dist x.nff --out " +
                 (dir / "n.png"));
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("unknown testbed 'nosuch' (known: today-pim, today-zephyr, ufmg1992)"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "n.png"));
  const std::string broken = dir / "broken.xml";
  std::ofstream(broken)
      << "<platform version=\"4.1\"><zone id=\"z\" routing=\"Full\"><host id=\"parent\"\n";
  r = RunCommand("bash " + Repo() + "/tools/testbed/simrun.sh --children 1 --platform " + broken +
                 " --zephyr " + SmpiPath() + " -- render --method dist x.nff");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find(broken), std::string::npos) << r.output;
}

}  // namespace
}  // namespace zephyr

namespace zephyr {
namespace {

// Every ray kind is one counted ray set-up (WorkEvent::kRay: primary, shadow, reflected and
// refracted alike): each kind alone, in any amount, adds exactly its count.
TEST(TestbedWork, EveryRayKindIsCountedAsARay) {
  for (int kind = 0; kind < kRayKinds; ++kind)
    for (uint64_t n : {uint64_t(1), uint64_t(7), uint64_t(1) << 40}) {
      TraceStats s;
      s.rays[kind] = n;
      const std::vector<double> c = testbed::EventCounts(s);
      EXPECT_EQ(c[int(testbed::WorkEvent::kRay)], double(n)) << "ray kind " << kind;
      double others = 0;
      for (int e = 0; e < testbed::kWorkEvents; ++e)
        if (e != int(testbed::WorkEvent::kRay)) others += c[e];
      EXPECT_EQ(others, 0) << "ray kind " << kind;
    }
  TraceStats all;
  for (int kind = 0; kind < kRayKinds; ++kind) all.rays[kind] = uint64_t(10) << kind;
  EXPECT_EQ(testbed::EventCounts(all)[int(testbed::WorkEvent::kRay)], 10 + 20 + 40 + 80);
}

}  // namespace
}  // namespace zephyr
