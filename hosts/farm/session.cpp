#include "hosts/farm/session.h"

#define OMPI_SKIP_MPICXX 1  // the C API only
#include <mpi.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <list>
#include <thread>

#include "fixed/check.h"

namespace zephyr {

namespace {
void CheckMpi(int code, const char* what) {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  throw UserError(std::string("MPI ") + what + " failed: " + std::string(text, length));
}

}  // namespace

struct MpiSession::PendingSends {
  struct Send {
    MPI_Request request;
    std::vector<std::byte> message;
  };
  std::list<Send> sends;  // to gone ranks too: they may never complete
};

void FinalizeMpiAtExit() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (finalized) return;
  MpiSession& mpi = MpiSession::Get();
  if (mpi.rank_ != 0 && mpi.leaveWithoutFinalize_) {
    // The parent lost a child and leaves without MPI_Finalize; mpirun then ends the job.
    // A child inside MPI_Finalize at that moment can wedge mpirun 4.1.4 for good (its PMIx
    // server deadlocks in PMIx_server_finalize with the ranks left as zombies; seen in
    // MpiCheck.AHungChildIsLostAfterTheTimeoutAndItsFramesReRendered), so this child hands
    // over its last messages and waits outside MPI to be ended with the job.
    mpi.FlushSends(10);
    std::fflush(stdout);
    std::fflush(stderr);
    std::this_thread::sleep_for(std::chrono::seconds(60));
    std::_Exit(3);
  }
  mpi.ReleaseChildren();
  mpi.DrainChildren();
  if (mpi.lostChild_ || !mpi.FlushSends(10)) {
    // MPI_Finalize would wait for a lost child (and for sends to it) forever, and MPI_Abort
    // has been seen to wedge mpirun 4.1.4; a rank that exits without finalizing makes mpirun
    // end the job.
    std::fprintf(stderr,
                 "zephyr: a child was lost; leaving without MPI_Finalize so that "
                 "mpirun ends the job (status 3)\n");
    std::fflush(stdout);
    std::fflush(stderr);
    std::_Exit(3);
  }
  MPI_Finalize();
}

// Children that were stopped early (the parent failed) may still be sending results or
// their stats; a big message goes by rendezvous and the child cannot finish until it is
// received. Take and drop what arrives until the children are quiet.
void MpiSession::DrainChildren() {
  if (rank_ != 0) return;
  auto unfinished = [&] {
    for (int r = 1; r < size_; ++r)
      if (!finished_[r] && !gone_[r]) return true;
    return false;
  };
  const auto start = std::chrono::steady_clock::now();
  auto lastMessage = start;
  auto since = [](auto t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  PollBackoff backoff;
  while (unfinished() && since(start) < 5 && since(lastMessage) < 0.3) {
    Progress();
    int flag = 0;
    MPI_Status status;
    if (MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status) != MPI_SUCCESS)
      return;
    if (!flag) {
      backoff.Wait();
      continue;
    }
    int count = 0;
    MPI_Get_count(&status, MPI_BYTE, &count);
    std::vector<std::byte> message(std::size_t(count < 0 ? 0 : count));
    MPI_Recv(message.data(), count, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    lastMessage = std::chrono::steady_clock::now();
    backoff.Reset();
  }
}

void MpiSession::MarkGone(int rank) {
  released_[rank] = true;
  gone_[rank] = true;
  lostChild_ = true;
}

MpiSession& MpiSession::Get() {
  static MpiSession* session = new MpiSession;  // never destroyed: used by the at-exit hook
  return *session;
}

MpiSession::MpiSession() : pending_(new PendingSends) {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) {
    CheckMpi(MPI_Init(nullptr, nullptr), "MPI_Init");
#ifndef ZEPHYR_SMPI
    std::atexit(FinalizeMpiAtExit);
#endif
    // Under SimGrid (zephyr-smpi, docs/testbed.md) a rank is a simulated actor: MPI_Finalize
    // from an at-exit hook runs after the simulation and crashes, so main() and a child's
    // exit finalize explicitly instead.
  }
  // Errors come back as codes (turned into UserError) instead of aborting the job, so the
  // parent can say what happened and keep its checkpoint.
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  char name[MPI_MAX_PROCESSOR_NAME];
  int length = 0;
  MPI_Get_processor_name(name, &length);
  host_.assign(name, length);
  sentSequence_.assign(size_, 0);
  receivedSequence_.assign(size_, 0);
  released_.assign(size_, false);
  gone_.assign(size_, false);
  finished_.assign(size_, false);
}

void MpiSession::ReleaseChildren() {
  if (rank_ != 0) return;
  TrafficAccount unused;
  for (int r = 1; r < size_; ++r) {
    if (released_[r]) continue;
    try {
      Send(r, {.kind = MessageKind::kStop, .aux = lostChild_ ? kStopWithoutFinalize : 0}, {},
           unused);
    } catch (const UserError&) {
      released_[r] = true;
    }
  }
}

void MpiSession::Send(int rank, MessageHeader header, std::span<const std::byte> payload,
                      TrafficAccount& account) {
  ZEPHYR_CHECK(rank >= 0 && rank < size_ && rank != rank_);
  header.payloadBytes = payload.size();
  header.sequence = sentSequence_[rank]++;
  auto& send = pending_->sends.emplace_back();
  send.message = EncodeMessage(header, payload);
  // The tag is the kind, for anyone watching the traffic; the receiver trusts the header.
  CheckMpi(MPI_Isend(send.message.data(), int(send.message.size()), MPI_BYTE, rank,
                     int(header.kind), MPI_COMM_WORLD, &send.request),
           "send");
  Progress();
  account.Add(header.kind, payload.size());
  if (header.kind == MessageKind::kStop) released_[rank] = true;
}

void MpiSession::Progress() {
  for (auto it = pending_->sends.begin(); it != pending_->sends.end();) {
    int done = 0;
    CheckMpi(MPI_Test(&it->request, &done, MPI_STATUS_IGNORE), "send");
    it = done ? pending_->sends.erase(it) : std::next(it);
  }
}

bool MpiSession::FlushSends(double timeoutSeconds) {
  auto start = std::chrono::steady_clock::now();
  PollBackoff backoff;
  for (;;) {
    Progress();
    if (pending_->sends.empty()) return true;
    if (lostChild_) return false;  // sends to a lost child may never complete
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
        timeoutSeconds)
      return false;
    backoff.Wait();
  }
}

std::optional<ReceivedMessage> MpiSession::TryReceive(int source, TrafficAccount& account) {
  Progress();
  int flag = 0;
  MPI_Status status;
  CheckMpi(
      MPI_Iprobe(source < 0 ? MPI_ANY_SOURCE : source, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status),
      "probe");
  if (!flag) return std::nullopt;
  int count = 0;
  MPI_Get_count(&status, MPI_BYTE, &count);
  std::vector<std::byte> message(std::size_t(count < 0 ? 0 : count));
  CheckMpi(MPI_Recv(message.data(), count, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG,
                    MPI_COMM_WORLD, MPI_STATUS_IGNORE),
           "receive");
  ReceivedMessage received;
  received.source = status.MPI_SOURCE;
  const std::string sender = "rank " + std::to_string(received.source);
  received.header = DecodeHeader(message, sender);
  if (status.MPI_TAG != int(received.header.kind))
    throw UserError("malformed message from " + sender + ": tag " + std::to_string(status.MPI_TAG) +
                    " disagrees with its header's kind");
  if (received.header.sequence != receivedSequence_[received.source])
    throw UserError("unexpected message from " + sender + ": sequence number " +
                    std::to_string(received.header.sequence) + ", expected " +
                    std::to_string(receivedSequence_[received.source]));
  ++receivedSequence_[received.source];
  if (received.header.kind == MessageKind::kStats || received.header.kind == MessageKind::kFailed)
    finished_[received.source] = true;
  received.payload.assign(message.begin() + MessageHeader::kBytes, message.end());
  account.Add(received.header.kind, received.payload.size());
  return received;
}

std::optional<ReceivedMessage> MpiSession::Receive(int source, TrafficAccount& account,
                                                   double timeoutSeconds) {
  auto start = std::chrono::steady_clock::now();
  PollBackoff backoff;
  for (;;) {
    if (auto m = TryReceive(source, account)) return m;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
        timeoutSeconds)
      return std::nullopt;
    backoff.Wait();
  }
}

void PollBackoff::Wait() {
  if (micros_ == 0) {
    micros_ = 10;
    std::this_thread::yield();
    return;
  }
  // usleep, not std::this_thread::sleep_for: under SimGrid (zephyr-smpi) SMPI turns it into
  // a simulated sleep, so polling costs simulated time, not the simulation's wall time.
  ::usleep(useconds_t(micros_));
  micros_ = std::min(maxMicros_, micros_ * 2);
}

}  // namespace zephyr
