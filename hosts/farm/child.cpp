// hosts/farm/child.cpp — a farm child (ranks ≥ 1): set up once from the parent's set-up
// message, then render frame after frame until told to stop (docs/distributed.md).
#include <unistd.h>

#include <algorithm>
#include <cstdint>

#include "fixed/check.h"
#include "hosts/farm/common.h"
#include "hosts/farm/farm.h"
#include "hosts/farm/test_fault.h"

namespace zephyr {

using namespace farm;

namespace {

// The child loop (ranks ≥ 1): returns when the parent says stop, or after reporting a failure.
void ServeFrames(const FrameWorkFactory& factory, const std::optional<TestFault>& fault) {
  MpiSession& mpi = MpiSession::Get();
  ZEPHYR_CHECK(mpi.Rank() != 0);
  TrafficAccount sent, received;
  auto fail = [&](const std::string& why) {
    mpi.Send(0, {.kind = MessageKind::kFailed}, Bytes(why), sent);
    mpi.FlushSends(3600);
  };
  auto next = [&]() {
    for (;;)
      if (auto m = mpi.Receive(0, received, 3600)) return *m;
  };

  ReceivedMessage first = next();
  if (first.header.kind == MessageKind::kStop) {  // nothing for this child
    if (first.header.aux == kStopWithoutFinalize) mpi.LeaveWithoutFinalize();
    return;
  }
  if (first.header.kind != MessageKind::kSetup)
    return fail(std::string("expected a setup message first, got ") +
                MessageKindName(first.header.kind));
  auto start = Clock::now();
  std::unique_ptr<FrameWork> work;
  try {
    work = factory(Text(first.payload));
  } catch (const UserError& e) {
    return fail(std::string("set-up failed: ") + e.what());
  }
  const double setupSeconds = SecondsSince(start);
  nlohmann::json ready = {{"pid", long(::getpid())}, {"host", mpi.Host()}};
  mpi.Send(0, {.kind = MessageKind::kReady}, Bytes(ready.dump()), sent);

  double busy = 0;
  std::uint64_t frames = 0, pixels = 0;
  std::vector<std::byte> out;
  auto loopStart = Clock::now();
  for (;;) {
    ReceivedMessage m = next();
    if (m.header.kind == MessageKind::kStop) {
      if (m.header.aux == kStopWithoutFinalize) mpi.LeaveWithoutFinalize();
      break;
    }
    if (m.header.kind != MessageKind::kWork)
      return fail(std::string("unexpected ") + MessageKindName(m.header.kind) + " message");
    Frame frame;
    try {
      frame = ReadRect(m.payload, m.header.frameId);
    } catch (const UserError& e) {
      return fail(e.what());
    }
    const bool inside = frame.id >= 0 && frame.width >= 1 && frame.height >= 1 && frame.x0 >= 0 &&
                        frame.y0 >= 0 && frame.x0 <= work->ImageWidth() - frame.width &&
                        frame.y0 <= work->ImageHeight() - frame.height;
    if (!inside)
      return fail("malformed work message: frame " + std::to_string(frame.id) +
                  " is not inside the image");
    const std::size_t sliceBytes = frame.PixelCount() * work->SliceBytesPerPixel();
    if (m.payload.size() != kRectBytes + sliceBytes)
      return fail("malformed work message: frame " + std::to_string(frame.id) + " carries " +
                  std::to_string(m.payload.size() - kRectBytes) + " matrix bytes, expected " +
                  std::to_string(sliceBytes));
    if (fault && fault->StrikeFails(mpi.Rank(), frames))
      return fail("injected failure (ZEPHYR_TEST_FAULT)");
    if (fault && fault->StrikeSendsGarbage(mpi.Rank(), frames)) {
      std::byte junk[3] = {};
      mpi.Send(0, {.kind = MessageKind::kResult, .frameId = frame.id}, junk, sent);
      continue;
    }
    auto t = Clock::now();
    out.assign(kRectBytes + frame.PixelCount() * work->BytesPerPixel(), std::byte{0});
    out.resize(0);
    AppendRect(frame, out);
    out.resize(kRectBytes + frame.PixelCount() * work->BytesPerPixel());
    try {
      work->RenderFrame(frame, std::span(m.payload).subspan(kRectBytes),
                        std::span(out).subspan(kRectBytes));
    } catch (const UserError& e) {
      return fail("frame " + std::to_string(frame.id) + ": " + e.what());
    }
    const double seconds = SecondsSince(t);
    busy += seconds;
    ++frames;
    pixels += frame.PixelCount();
    mpi.Send(
        0, {.kind = MessageKind::kResult, .frameId = frame.id, .aux = std::uint64_t(seconds * 1e9)},
        out, sent);
  }
  const double loopSeconds = SecondsSince(loopStart);
  // The stats message counts itself among the sent bytes: its size is known before sending
  // only up to the digits of the numbers, so count it first, then measure.
  nlohmann::json stats = {{"frames", frames},
                          {"pixels", pixels},
                          {"setupSeconds", setupSeconds},
                          {"busySeconds", busy},
                          {"idleSeconds", std::max(0.0, loopSeconds - busy)},
                          {"received", received.ToJson()},
                          {"work", work->Stats()}};
  stats["sent"] = sent.ToJson();  // everything before this stats message
  mpi.Send(0, {.kind = MessageKind::kStats}, Bytes(stats.dump()), sent);
  mpi.FlushSends(3600);
}

}  // namespace

MpiSession& farm::StartFarm(const std::string& method) {
  MpiSession& mpi = MpiSession::Get();
  if (mpi.Size() < 2)
    throw UserError("method '" + method + "'" +
                    " needs at least 2 MPI ranks (a parent and one "
                    "child) but runs on " +
                    std::to_string(mpi.Size()) +
                    "; launch it with `mpirun -np K+1 zephyr render ...` or `make run WORKERS=K`");
  return mpi;
}

bool ServeIfChild(const std::string& method, const FrameWorkFactory& factory) {
  if (StartFarm(method).Rank() == 0) return false;
  ServeFrames(factory, TestFault::FromEnvironment());
  return true;
}

}  // namespace zephyr
