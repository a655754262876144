// hosts/farm/protocol.h — the messages between the parent (rank 0) and its children.
//
// Every message is one MPI message of bytes: a fixed 40-byte header (the "envelope") and
// then the payload. The header says what the message is and how long its payload is; a
// receiver checks every field (magic, version, kind, direction, sizes, frame id) before it
// trusts a byte of the payload. See docs/distributed.md for the layout.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <span>
#include <string>
#include <vector>

namespace zephyr {

enum class MessageKind : std::uint16_t {
  kSetup = 1,   // parent→child, once: the opaque job description the child builds its work from
  kReady = 2,   // child→parent, once: {pid, host} after the set-up succeeded
  kWork = 3,    // parent→child: frame rectangle + (hetero) the frame's slice of the pixel matrix
  kResult = 4,  // child→parent: frame rectangle + the frame's pixels; aux = busy nanoseconds
  kStop = 5,    // parent→child: no more work; aux = kStopWithoutFinalize when a child was lost
  kStats = 6,   // child→parent, last: the child's own counters (JSON)
  kFailed = 7,  // child→parent: the child could not go on; payload = the error text
};
inline constexpr int kMessageKindCount = 7;
// kStop's aux when a child was lost: the job ends without MPI_Finalize (the parent leaves
// with status 3 and mpirun ends the job), so the child must not enter MPI_Finalize either
// (docs/distributed.md, "What OpenMPI 4.1 does around this").
inline constexpr std::uint64_t kStopWithoutFinalize = 1;
const char* MessageKindName(MessageKind kind);
// Which way a kind travels; the receiver rejects a kind coming the wrong way.
bool TravelsToChild(MessageKind kind);

struct MessageHeader {
  static constexpr std::uint32_t kMagic = 0x4D48505A;  // "ZPHM" little-endian
  static constexpr std::uint16_t kVersion = 1;
  static constexpr std::size_t kBytes = 40;
  // A payload bigger than this is refused (a frame of 4096² float RGB pixels is 192 MiB).
  static constexpr std::uint64_t kMaxPayload = std::uint64_t(1) << 30;

  MessageKind kind = MessageKind::kStop;
  std::int32_t frameId = -1;  // -1 when the message is not about one frame
  std::uint64_t payloadBytes = 0;
  std::uint64_t aux = 0;       // kind-specific (kResult: child busy time in ns)
  std::uint64_t sequence = 0;  // per sender, 0, 1, 2...: a lost or duplicated message shows
};

// The whole message: header then payload.
std::vector<std::byte> EncodeMessage(const MessageHeader& header,
                                     std::span<const std::byte> payload);
// Checks and splits a received message; throws UserError naming the sender and what was
// wrong (short message, bad magic/version/kind, payload size disagreeing with the header).
MessageHeader DecodeHeader(std::span<const std::byte> message, const std::string& sender);

// A frame rectangle as it travels in kWork and kResult payloads: 4 little-endian int32.
inline constexpr std::size_t kRectBytes = 16;
struct Frame;
void AppendRect(const Frame& frame, std::vector<std::byte>& out);
Frame ReadRect(std::span<const std::byte> payload, int frameId);

// Bytes sent one way, by kind: payload and envelope separately, and the message count.
struct TrafficCount {
  std::uint64_t messages = 0, payloadBytes = 0, envelopeBytes = 0;
};
class TrafficAccount {
 public:
  void Add(MessageKind kind, std::uint64_t payloadBytes);
  const TrafficCount& Of(MessageKind kind) const { return counts_[int(kind) - 1]; }
  TrafficCount Total() const;
  TrafficAccount& operator+=(const TrafficAccount& other);
  // {"setup": {"messages":..,"payloadBytes":..,"envelopeBytes":..}, ..., "total": {...}}
  nlohmann::json ToJson() const;
  static TrafficAccount FromJson(const nlohmann::json& j);  // throws UserError if malformed

 private:
  std::array<TrafficCount, kMessageKindCount> counts_{};
};

}  // namespace zephyr
