// hosts/farm/parent.cpp — the farm's parent (rank 0): the frame queue, handing frames out on
// demand, losing and replacing children, the checkpoint, and the report (docs/distributed.md,
// "Accounting" and "Faults, timeouts, resume").
#include <fmt/core.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <deque>

#include "fixed/check.h"
#include "hosts/farm/checkpoint.h"
#include "hosts/farm/common.h"
#include "hosts/farm/farm.h"

namespace zephyr {

using namespace farm;

namespace {

double CpuSeconds() {  // this process, user + system
  rusage u;
  ::getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

std::string FrameList(const std::vector<int>& ids) {
  std::string s;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (i == 20) return s + ", … (" + std::to_string(ids.size()) + " in all)";
    s += (i ? ", " : "") + std::to_string(ids[i]);
  }
  return s;
}

struct ChildState {
  int rank = 0;
  bool alive = true;
  bool ready = false;
  bool stopped = false;
  bool setUp = false;  // got the set-up message (a child that did not only gets a stop)
  long pid = -1;
  std::string host;
  std::deque<int> inFlight;
  Clock::time_point lastProgress;
  std::uint64_t frames = 0, pixels = 0;
  double busyFromResults = 0;
  std::optional<ChildReport::Stats> stats;
  std::string lostReason;
};

class Parent {
 public:
  Parent(const FramedJob& job, const FramedOptions& options)
      : job_(job),
        options_(options),
        mpi_(MpiSession::Get()),
        grid_(job.imageWidth, job.imageHeight, job.frameSize),
        done_(grid_.Count(), false) {
    ZEPHYR_CHECK(mpi_.Rank() == 0);
    ZEPHYR_CHECK(job.bytesPerPixel > 0);
    if (options.framesInFlight < 1) throw UserError("frames in flight must be at least 1");
    if (!(options.childTimeoutSeconds > 0)) throw UserError("child timeout must be positive");
    image_.assign(std::size_t(job.imageWidth) * job.imageHeight * job.bytesPerPixel, std::byte{0});
    for (int r = 1; r < mpi_.Size(); ++r) {
      children_.emplace_back();
      children_.back().rank = r;
    }
  }

  FramedResult Run();

 private:
  void OpenCheckpoint();
  void Dispatch(ChildState& child);
  void Handle(ReceivedMessage& m);
  void CheckChildren();
  void Lose(ChildState& child, const std::string& reason);
  void StopAll();
  void CollectStats();
  [[noreturn]] void Abandon(const std::string& why);
  FarmReport Report() const;
  ChildState& Child(int rank) { return children_[rank - 1]; }

  const FramedJob& job_;
  const FramedOptions& options_;
  MpiSession& mpi_;
  FrameGrid grid_;
  std::vector<bool> done_;
  int doneCount_ = 0;
  std::vector<std::byte> image_;
  std::vector<std::optional<std::vector<std::byte>>> slices_;  // hetero: per frame id
  std::optional<FrameCheckpoint> checkpoint_;
  FrameQueue queue_{{}};
  std::vector<ChildState> children_;
  TrafficAccount sent_, received_;
  std::vector<int> skipped_, lost_;
  int resumed_ = 0, ignoredMessages_ = 0;
  int checkpointed_ = 0;            // frames in the checkpoint file (degenerate ones never are)
  std::vector<int> checkpointBad_;  // --resume: frames whose records were damaged
  double distributionSeconds_ = 0, distributionCpuSeconds_ = 0;
};

void Parent::OpenCheckpoint() {
  if (options_.checkpointPath.empty()) {
    if (options_.resume) throw UserError("resuming a farm needs an output file (its checkpoint)");
    return;
  }
  CheckpointKey key{job_.imageWidth, job_.imageHeight, job_.frameSize,
                    std::uint32_t(job_.bytesPerPixel), JobHash(job_.method + '\n' + job_.setup)};
  if (!options_.resume) {
    if (::access(options_.checkpointPath.c_str(), F_OK) == 0)
      std::fprintf(stderr,
                   "zephyr: note: replacing the checkpoint %s of an earlier run (--resume "
                   "would keep its frames)\n",
                   options_.checkpointPath.c_str());
    checkpoint_.emplace(FrameCheckpoint::Create(options_.checkpointPath, key));
    return;
  }
  checkpoint_.emplace(FrameCheckpoint::Resume(options_.checkpointPath, key));
  std::vector<int> bad = checkpoint_->Damage().badFrames;
  for (const auto& [id, pixels] : checkpoint_->Frames()) {
    if (id < 0 || id >= grid_.Count() ||
        pixels.size() != grid_.At(id).PixelCount() * job_.bytesPerPixel) {
      bad.push_back(id);  // intact checksums, but not a frame of this job: render it again
      continue;
    }
    PasteFrame(grid_.At(id), pixels, image_, job_.imageWidth, job_.bytesPerPixel);
    done_[id] = true;
    ++doneCount_;
    ++resumed_;
    ++checkpointed_;
  }
  checkpointBad_ = bad;
  const CheckpointDamage& damage = checkpoint_->Damage();
  if (damage.Any() || !bad.empty())
    std::fprintf(stderr,
                 "zephyr: warning: checkpoint %s: %d intact frames kept; %zu bad record(s)%s%s, "
                 "%zu unreadable bytes in %d place(s) skipped; every missing frame is rendered "
                 "again\n",
                 options_.checkpointPath.c_str(), resumed_, bad.size(),
                 bad.empty() ? "" : " for frames ", FrameList(bad).c_str(), damage.unreadableBytes,
                 damage.unreadableRegions);
}

void Parent::Dispatch(ChildState& child) {
  if (!child.alive) return;
  if (child.inFlight.empty()) child.lastProgress = Clock::now();
  while (int(child.inFlight.size()) < options_.framesInFlight && !queue_.Empty()) {
    int id = queue_.Next();
    if (done_[id]) continue;  // a re-queued frame that its first child finished after all
    Frame frame = grid_.At(id);
    std::vector<std::byte> payload;
    AppendRect(frame, payload);
    if (slices_[id]) payload.insert(payload.end(), slices_[id]->begin(), slices_[id]->end());
    mpi_.Send(child.rank, {.kind = MessageKind::kWork, .frameId = id}, payload, sent_);
    child.inFlight.push_back(id);
  }
}

void Parent::Handle(ReceivedMessage& m) {
  const std::string sender = "child rank " + std::to_string(m.source);
  if (m.source < 1 || m.source >= mpi_.Size()) Abandon("message from unknown rank");
  ChildState& child = Child(m.source);
  if (!child.alive) {  // declared lost, then answered after all: its frames went elsewhere
    ++ignoredMessages_;
    return;
  }
  switch (m.header.kind) {
    case MessageKind::kReady: {
      if (child.ready) Abandon("unexpected second ready message from " + sender);
      try {
        auto j = nlohmann::json::parse(Text(m.payload));
        child.pid = j.at("pid").get<long>();
        child.host = j.at("host").get<std::string>();
      } catch (const nlohmann::json::exception& e) {
        Abandon("malformed ready message from " + sender + ": " + e.what());
      }
      child.ready = true;
      return;
    }
    case MessageKind::kResult: {
      const int id = m.header.frameId;
      auto it = std::find(child.inFlight.begin(), child.inFlight.end(), id);
      if (it == child.inFlight.end())
        Abandon("unexpected result from " + sender + " for frame " + std::to_string(id) +
                ", which it was not given");
      const Frame frame = grid_.At(id);
      const std::size_t expected = kRectBytes + frame.PixelCount() * job_.bytesPerPixel;
      if (m.payload.size() != expected)
        Abandon("malformed result from " + sender + " for frame " + std::to_string(id) + ": " +
                std::to_string(m.payload.size()) + " payload bytes, expected " +
                std::to_string(expected));
      if (ReadRect(m.payload, id) != frame)
        Abandon("malformed result from " + sender + ": frame " + std::to_string(id) +
                " comes back with a different rectangle");
      child.inFlight.erase(it);
      child.lastProgress = Clock::now();
      child.busyFromResults += double(m.header.aux) * 1e-9;
      if (!done_[id]) {
        auto pixels = std::span(m.payload).subspan(kRectBytes);
        PasteFrame(frame, pixels, image_, job_.imageWidth, job_.bytesPerPixel);
        if (job_.pasted) job_.pasted(frame);
        if (checkpoint_) {
          try {
            checkpoint_->Append(id, pixels);
          } catch (const UserError& e) {
            Abandon(e.what());  // e.g. a full disk: the frames already written stay
          }
          ++checkpointed_;
        }
        done_[id] = true;
        ++doneCount_;
        ++child.frames;
        child.pixels += frame.PixelCount();
      }
      Dispatch(child);
      return;
    }
    case MessageKind::kFailed:
      child.alive = false;  // it has left its loop

      Abandon(sender + " failed: " + Text(m.payload));
    default:
      Abandon(std::string("unexpected ") + MessageKindName(m.header.kind) + " message from " +
              sender);
  }
}

void Parent::Lose(ChildState& child, const std::string& reason) {
  child.alive = false;
  mpi_.MarkGone(child.rank);
  child.lostReason = reason;
  std::vector<int> frames(child.inFlight.begin(), child.inFlight.end());
  for (auto it = child.inFlight.rbegin(); it != child.inFlight.rend(); ++it) queue_.Requeue(*it);
  child.inFlight.clear();
  lost_.insert(lost_.end(), frames.begin(), frames.end());
  std::fprintf(stderr,
               "zephyr: warning: child rank %d (pid %ld on %s) lost: %s; its frames %s go back "
               "to the queue\n",
               child.rank, child.pid, child.host.empty() ? "?" : child.host.c_str(), reason.c_str(),
               frames.empty() ? "(none)" : FrameList(frames).c_str());
  for (ChildState& other : children_) Dispatch(other);
}

// A child is lost when it holds frames and has not answered for the timeout, or — on this
// host, where its pid means something — as soon as its process is gone.
void Parent::CheckChildren() {
  for (ChildState& child : children_) {
    if (!child.alive) continue;
#ifndef ZEPHYR_SMPI  // simulated ranks are actors of one process: their pids are SimGrid's
    if (child.pid > 0 && child.host == mpi_.Host() && ::kill(pid_t(child.pid), 0) != 0 &&
        errno == ESRCH) {
      Lose(child, "its process has exited");
      continue;
    }
#endif
    if (!child.inFlight.empty() && SecondsSince(child.lastProgress) > options_.childTimeoutSeconds)
      Lose(child, fmt::format("no answer within the {:g} s timeout", options_.childTimeoutSeconds));
  }
}

void Parent::StopAll() {
  for (ChildState& child : children_) {
    if (!child.alive || child.stopped) continue;
    try {
      mpi_.Send(child.rank,
                {.kind = MessageKind::kStop, .aux = mpi_.LostChild() ? kStopWithoutFinalize : 0},
                {}, sent_);
    } catch (const UserError&) {
      child.alive = false;
    }
    child.stopped = true;
    if (!child.setUp) mpi_.MarkFinished(child.rank);  // it leaves on the stop, silently
  }
}

void Parent::Abandon(const std::string& why) {
  StopAll();
  std::vector<int> missing;
  for (int id = 0; id < grid_.Count(); ++id)
    if (!done_[id]) missing.push_back(id);
  std::string message = why + "; " + std::to_string(missing.size()) + " of " +
                        std::to_string(grid_.Count()) + " frames missing (" + FrameList(missing) +
                        ")";
  if (checkpoint_)
    message += "; the " + std::to_string(checkpointed_) + " rendered frames are kept in " +
               checkpoint_->Path() + " — rerun with --resume to render only the missing ones";
  throw UserError(message);
}

void Parent::CollectStats() {
  auto start = Clock::now();
  PollBackoff backoff;
  auto waiting = [&] {
    return std::count_if(children_.begin(), children_.end(), [](const ChildState& c) {
      return c.alive && c.setUp && c.stopped && !c.stats;
    });
  };
  while (waiting() > 0) {
    if (SecondsSince(start) > options_.childTimeoutSeconds) {
      for (ChildState& c : children_)
        if (c.alive && c.setUp && !c.stats) c.lostReason = "no stats after stop";
      return;
    }
    auto m = mpi_.TryReceive(-1, received_);
    if (!m) {
      backoff.Wait();
      continue;
    }
    if (m->source < 1 || m->source >= mpi_.Size()) Abandon("message from unknown rank");
    ChildState& child = Child(m->source);
    if (m->header.kind == MessageKind::kReady && !child.ready) {
      Handle(*m);
      continue;
    }
    if (m->header.kind != MessageKind::kStats || !child.alive) {
      ++ignoredMessages_;
      continue;
    }
    try {
      const nlohmann::json j = nlohmann::json::parse(Text(m->payload));
      child.stats = ChildReport::Stats{.framesRendered = j.value("frames", 0),
                                       .setupSeconds = j.value("setupSeconds", 0.0),
                                       .busySeconds = j.at("busySeconds").get<double>(),
                                       .idleSeconds = j.at("idleSeconds").get<double>(),
                                       .sent = TrafficAccount::FromJson(j.at("sent")),
                                       .received = TrafficAccount::FromJson(j.at("received")),
                                       .work = j.value("work", nlohmann::json::object())};
    } catch (const nlohmann::json::exception& e) {
      throw UserError("malformed stats message from child rank " + std::to_string(child.rank) +
                      ": " + e.what());
    }
  }
}

FramedResult Parent::Run() {
  OpenCheckpoint();
  auto start = Clock::now();
  const double cpuStart = CpuSeconds();
  slices_.resize(grid_.Count());
  std::vector<int> pending;
  for (int id = 0; id < grid_.Count(); ++id) {
    if (done_[id]) continue;
    const Frame frame = grid_.At(id);
    if (job_.sliceFor) {
      slices_[id] = job_.sliceFor(frame);
      if (!slices_[id]) {  // degenerate: no primary hit, background, no message
        std::vector<std::byte> pixels(frame.PixelCount() * job_.bytesPerPixel);
        job_.fillDegenerate(frame, pixels);
        PasteFrame(frame, pixels, image_, job_.imageWidth, job_.bytesPerPixel);
        done_[id] = true;
        ++doneCount_;
        skipped_.push_back(id);
        continue;
      }
    }
    pending.push_back(id);
  }
  queue_ = FrameQueue(pending);
  for (ChildState& child : children_) {
    if (queue_.Empty()) break;  // children with nothing to do only get a stop
    mpi_.Send(child.rank, {.kind = MessageKind::kSetup}, Bytes(job_.setup), sent_);
    child.setUp = true;
    Dispatch(child);
  }
  PollBackoff backoff;
  auto lastCheck = Clock::now();
  while (doneCount_ < grid_.Count()) {
    if (auto m = mpi_.TryReceive(-1, received_)) {
      Handle(*m);
      backoff.Reset();
      continue;
    }
    if (SecondsSince(lastCheck) > 0.05) {
      CheckChildren();
      lastCheck = Clock::now();
      if (std::none_of(children_.begin(), children_.end(),
                       [](const ChildState& c) { return c.alive; }))
        Abandon("every child is lost");
    }
    backoff.Wait();
  }
  distributionSeconds_ = SecondsSince(start);
  distributionCpuSeconds_ = CpuSeconds() - cpuStart;
  StopAll();
  CollectStats();
  // The checkpoint stays: it is the only copy of the frames until the caller's outputs are
  // written (FramedResult::checkpointPath).
  return {std::move(image_), Report(), checkpoint_ ? checkpoint_->Path() : std::string()};
}

FarmReport Parent::Report() const {
  FarmReport r;
  r.method = job_.method;
  r.ranks = mpi_.Size(), r.children = mpi_.Size() - 1;
  r.frameSize = job_.frameSize, r.framesInFlight = options_.framesInFlight;
  r.childTimeoutSeconds = options_.childTimeoutSeconds;
  r.framesTotal = grid_.Count(), r.frameColumns = grid_.Columns(), r.frameRows = grid_.Rows();
  r.framesSent = int(sent_.Of(MessageKind::kWork).messages);
  r.skippedFrames = skipped_, r.resumedFrames = resumed_, r.damagedFrames = checkpointBad_;
  r.lostFrames = lost_;
  r.parentToChildren = sent_, r.childrenToParent = received_;
  r.ignoredMessages = ignoredMessages_;
  for (const ChildState& c : children_)
    r.perChild.push_back({.rank = c.rank,
                          .host = c.host,
                          .pid = c.pid,
                          .framesAccepted = c.frames,
                          .pixels = c.pixels,
                          .lostReason = c.lostReason,
                          .stats = c.stats});
  r.parentPassSeconds = job_.parentPassSeconds;
  r.distributionSeconds = distributionSeconds_, r.parentCpuSeconds = distributionCpuSeconds_;
  return r;
}

}  // namespace

FramedResult RenderFrames(const FramedJob& job, const FramedOptions& options) {
  StartFarm(job.method);
  Parent parent(job, options);
  return parent.Run();
}

}  // namespace zephyr

namespace zephyr {

double FarmReport::ChildrenBusySeconds() const {
  double busy = 0;
  for (const ChildReport& c : perChild)
    if (c.stats) busy += c.stats->busySeconds;
  return busy;
}

double FarmReport::ChildrenIdleSeconds() const {
  double idle = 0;
  for (const ChildReport& c : perChild)
    if (c.stats) idle += c.stats->idleSeconds;
  return idle;
}

nlohmann::json FarmReport::Json() const {
  nlohmann::json childList = nlohmann::json::array();
  for (const ChildReport& c : perChild) {
    nlohmann::json j = {{"rank", c.rank},     {"host", c.host},
                        {"pid", c.pid},       {"framesAccepted", c.framesAccepted},
                        {"pixels", c.pixels}, {"lost", !c.lostReason.empty()}};
    if (!c.lostReason.empty()) j["lostReason"] = c.lostReason;
    if (c.stats) {
      j["framesRendered"] = c.stats->framesRendered;
      j["setupSeconds"] = c.stats->setupSeconds;
      j["busySeconds"] = c.stats->busySeconds;
      j["idleSeconds"] = c.stats->idleSeconds;
      j["sent"] = c.stats->sent.ToJson();
      j["received"] = c.stats->received.ToJson();
      j["work"] = c.stats->work;
    }
    childList.push_back(j);
  }
  return {
      {"method", method},
      {"ranks", ranks},
      {"children", children},
      {"frameSize", frameSize},
      {"framesInFlight", framesInFlight},
      {"childTimeoutSeconds", childTimeoutSeconds},
      {"frames",
       {{"total", framesTotal},
        {"columns", frameColumns},
        {"rows", frameRows},
        {"sent", framesSent},
        {"skipped", skippedFrames.size()},
        {"skippedIds", skippedFrames},
        {"resumed", resumedFrames},
        {"checkpointDamaged", damagedFrames},
        {"lost", lostFrames}}},
      {"traffic",
       {{"parentToChildren", parentToChildren.ToJson()},
        {"childrenToParent", childrenToParent.ToJson()}}},
      {"ignoredMessages", ignoredMessages},
      {"perChild", childList},
      {"time",
       {{"parentPassSeconds", parentPassSeconds},
        {"distributionSeconds", distributionSeconds},
        {"parentCpuSeconds", parentCpuSeconds},
        {"childrenBusySeconds", ChildrenBusySeconds()},
        {"childrenIdleSeconds", ChildrenIdleSeconds()}}},
  };
}

}  // namespace zephyr
