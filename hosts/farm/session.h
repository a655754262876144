// hosts/farm/session.h — MPI, started only by the methods that need it.
//
// `zephyr render --method seq` never touches MPI; dist and hetero call MpiSession::Get(),
// which runs MPI_Init once (a program started without mpirun becomes a 1-rank "singleton"
// job) and MPI_Finalize at exit. Messages are byte vectors framed by mpi_protocol.h; every
// send and receive is counted in a TrafficAccount by kind.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hosts/farm/protocol.h"

namespace zephyr {

void FinalizeMpiAtExit();

struct ReceivedMessage {
  int source = -1;
  MessageHeader header;
  std::vector<std::byte> payload;
};

class MpiSession {
 public:
  static MpiSession& Get();  // MPI_Init on first use
  int Rank() const { return rank_; }
  int Size() const { return size_; }
  const std::string& Host() const { return host_; }

  // Sends header+payload to `rank` (header.payloadBytes and .sequence are filled in) and
  // counts it in `account`. Throws UserError if MPI reports an error. The send is
  // non-blocking (MPI_Isend; the message is kept until it completes): a big frame goes by
  // rendezvous, and a parent and a child each blocked sending to the other would deadlock.
  void Send(int rank, MessageHeader header, std::span<const std::byte> payload,
            TrafficAccount& account);
  // A message from `source` (or any rank when source < 0) if one is waiting; it is checked by
  // DecodeHeader (throws UserError when malformed) and counted in `account`.
  std::optional<ReceivedMessage> TryReceive(int source, TrafficAccount& account);
  // Waits for a message, sleeping between polls so a waiting process leaves its core to the
  // ones that compute (OpenMPI's blocking receive spins); gives up after timeoutSeconds.
  std::optional<ReceivedMessage> Receive(int source, TrafficAccount& account,
                                         double timeoutSeconds);

  // Completes what it can of the sends in progress (every receive poll does this too).
  void Progress();
  // Waits for the sends in progress; false if some are still pending after the timeout.
  bool FlushSends(double timeoutSeconds);

  // Rank 0: a lost child (dead, or not answering) is never sent anything again, not even
  // the final stop. It may never reach MPI_Finalize, so rank 0 then exits without it
  // (status 3) and mpirun ends the job (see docs/distributed.md).
  void MarkGone(int rank);
  // Rank 0: whether a child was lost (the job then ends without MPI_Finalize).
  bool LostChild() const { return lostChild_; }
  // A child told (by its stop) that a child was lost: at exit it sends what is pending and
  // waits outside MPI for mpirun to end the job instead of entering MPI_Finalize.
  void LeaveWithoutFinalize() { leaveWithoutFinalize_ = true; }
  // Rank 0: a child that was never set up and only got a stop sends nothing more.
  void MarkFinished(int rank) { finished_[rank] = true; }
  // Rank 0, at exit (also after an error): sends a stop to every child that has not had one,
  // so no child waits for work forever and MPI_Finalize can complete.
  void ReleaseChildren();
  // Rank 0, at exit: receives and drops what children still send (for up to 5 s, until
  // 0.3 s pass without a message), so none stays blocked in a send and all can finalize.
  void DrainChildren();

 private:
  MpiSession();
  int rank_ = 0, size_ = 1;
  std::string host_;
  std::vector<std::uint64_t> sentSequence_;      // per destination
  std::vector<std::uint64_t> receivedSequence_;  // per source
  std::vector<bool> released_;                   // per rank: sent a stop, or gone
  std::vector<bool> gone_, finished_;            // per rank: lost; sent its stats or failure
  bool lostChild_ = false;
  bool leaveWithoutFinalize_ = false;
  struct PendingSends;
  PendingSends* pending_;  // never freed, like the session
  friend void FinalizeMpiAtExit();
};

// Sleeps between polls: short right after activity, growing to `maxMicros` when idle.
class PollBackoff {
 public:
  explicit PollBackoff(int maxMicros = 1000) : maxMicros_(maxMicros) {}
  void Reset() { micros_ = 0; }
  void Wait();

 private:
  int micros_ = 0, maxMicros_;
};

}  // namespace zephyr
