#include "hosts/methods/farmed.h"

#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <utility>

#include "fixed/check.h"
#include "hosts/farm/checkpoint.h"
#include "hosts/farm/session.h"
#include "hosts/io/output_file.h"
#include "hosts/scene/nff.h"
#include "hosts/testbed/simulation.h"
#include "hosts/testbed/testbed.h"

namespace zephyr::farmed {

std::string SetupText(const std::string& method, const Scene& scene, const TraceOptions& trace,
                      const nlohmann::json& more) {
  nlohmann::json j = {{"method", method},
                      {"scene", WriteNff(scene)},
                      {"depth", trace.depth},
                      {"precision", kPrecisionNames.NameOf(trace.precision)},
                      {"sphereTest", kSphereTestNames.NameOf(trace.sphereTest)},
                      {"accel", kAccelNames.NameOf(trace.accel)}};
  j.update(more);
  return j.dump();
}

ChildSetup ReadSetup(const std::string& text, const std::string& method) {
  ChildSetup s;
  try {
    s.json = nlohmann::json::parse(text);
    const std::string got = s.json.at("method").get<std::string>();
    if (got != method)
      throw UserError("malformed set-up message: it is for method '" + got +
                      "', this child runs '" + method + "'");
    s.scene = ParseNffOrThrow(s.json.at("scene").get<std::string>(), "<scene from the parent>");
    s.trace.depth = s.json.at("depth").get<int>();
    s.trace.precision =
        kPrecisionNames.Parse(s.json.at("precision").get<std::string>(), "the set-up's precision");
    s.trace.sphereTest = kSphereTestNames.Parse(s.json.at("sphereTest").get<std::string>(),
                                                "the set-up's sphere test");
    s.trace.accel =
        kAccelNames.Parse(s.json.at("accel").get<std::string>(), "the set-up's acceleration");
  } catch (const nlohmann::json::exception& e) {
    throw UserError(std::string("malformed set-up message: ") + e.what());
  }
  return s;
}

void CheckDistOptions(const DistOptions& o) {
  if (o.frameSize < 1)
    throw UserError("--frame: the frame size must be a whole number of pixels ≥ 1, got '" +
                    std::to_string(o.frameSize) + "'");
  if (o.framesInFlight < 1) throw UserError("--in-flight: expected a whole number ≥ 1");
}

FramedOptions FarmOptions(const RenderOptions& o) {
  FramedOptions f;
  f.checkpointPath = o.out.empty() ? "" : CheckpointPathFor(o.out);
  f.resume = o.dist.resume;
  f.childTimeoutSeconds = o.dist.childTimeoutSeconds;
  // Under SimGrid wall-clock time means nothing to the simulated run: no timeout.
  if (testbed::Simulated()) f.childTimeoutSeconds = std::numeric_limits<double>::infinity();
  f.framesInFlight = o.dist.framesInFlight;
  return f;
}

void EndChild() {
  if (testbed::Simulated()) FinalizeMpiAtExit();  // no at-exit hook under SMPI (session.cpp)
  std::fflush(stdout);
  std::exit(0);
}

void CheckFarmOptions(const RenderOptions& o) {
  CheckDistOptions(o.dist);
  const FramedOptions f = FarmOptions(o);
  if (f.resume && o.out.empty())
    throw UserError("--resume needs --out: the frames it resumes are kept in OUT.frames");
  if (f.checkpointPath.empty()) return;
  for (const auto& [what, path] :
       {std::pair{"the scene", &o.scenePath}, std::pair{"--report", &o.report},
        std::pair{"--dump-primary", &o.dumpPrimary}})
    if (!path->empty() && SameFile(*path, f.checkpointPath))
      throw UserError(std::string(what) + " " + *path + " is the checkpoint of --out " + o.out +
                      " (" + f.checkpointPath + "); choose another name");
  struct stat s;
  const bool exists = ::stat(f.checkpointPath.c_str(), &s) == 0;
  if (exists && !S_ISREG(s.st_mode))
    throw UserError(f.checkpointPath + " (the checkpoint of --out " + o.out +
                    ") exists and is not a regular file");
  if (f.resume && !exists)
    throw UserError("nothing to resume: no checkpoint " + f.checkpointPath +
                    " (it is written by a run with the same --out)");
}

void ChildStats::AddFrame(const TraceStats& frame) {
  stats_.Add(frame);
  chargedSeconds_ += testbed::ChargeHostWork(frame);  // simulated testbed only
}

nlohmann::json ChildStats::Json() const {
  nlohmann::json j = stats_.ToJson();
  if (testbed::Simulated()) {
    // Simulated time of this child: charged work is busy, the rest waiting on the network
    // and the parent.
    const double now = testbed::SimulatedNow();
    j["testbed"] = testbed::SimulatedHost();
    j["testbed"]["busySeconds"] = chargedSeconds_;
    j["testbed"]["idleSeconds"] = now - chargedSeconds_;
    j["testbed"]["clockAtStats"] = now;
  }
  return j;
}

testbed::FarmTimes FarmTimesOf(const FarmReport& report) {
  testbed::FarmTimes t;
  t.parentPassSeconds = report.parentPassSeconds;
  for (const ChildReport& c : report.perChild) {
    testbed::FarmTimes::Child child{.rank = c.rank, .host = c.host};
    // Decoding the child's stats message: "work"."testbed"."busySeconds" (simulated only).
    try {
      if (c.stats && c.stats->work.contains("testbed"))
        child.busySeconds = c.stats->work.at("testbed").at("busySeconds").get<double>();
    } catch (const nlohmann::json::exception& e) {
      throw UserError("malformed stats message from child rank " + std::to_string(c.rank) + ": " +
                      e.what());
    }
    t.children.push_back(child);
  }
  return t;
}

void ChargeParentPixels(std::uint64_t pixels) {
  if (!testbed::Simulated()) return;
  TraceStats work;
  work.pixels = pixels;
  testbed::ChargeHostWork(work);
}

Image ToImage(const std::vector<std::byte>& bytes, int width, int height) {
  Image image(width, height);
  ZEPHYR_CHECK_EQ(bytes.size(), image.pixels.size() * kPixelBytes);
  std::memcpy(image.pixels.data(), bytes.data(), bytes.size());
  return image;
}

}  // namespace zephyr::farmed
