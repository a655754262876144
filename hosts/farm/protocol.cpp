#include "hosts/farm/protocol.h"

#include <bit>
#include <cstring>
#include <nlohmann/json.hpp>

#include "fixed/check.h"
#include "fixed/named.h"
#include "hosts/farm/frame.h"

namespace zephyr {

namespace {
template <typename T>
void Put(std::byte* at, T value) {  // little-endian hosts only (x86-64, checked below)
  static_assert(std::endian::native == std::endian::little);
  std::memcpy(at, &value, sizeof value);
}
template <typename T>
T Get(const std::byte* at) {
  T value;
  std::memcpy(&value, at, sizeof value);
  return value;
}
}  // namespace

const char* MessageKindName(MessageKind kind) {
  static constexpr NamedValues<MessageKind, kMessageKindCount> kNames{
      {{{MessageKind::kSetup, "setup"},
        {MessageKind::kReady, "ready"},
        {MessageKind::kWork, "work"},
        {MessageKind::kResult, "result"},
        {MessageKind::kStop, "stop"},
        {MessageKind::kStats, "stats"},
        {MessageKind::kFailed, "failed"}}}};
  return kNames.NameOf(kind);
}

bool TravelsToChild(MessageKind kind) {
  return kind == MessageKind::kSetup || kind == MessageKind::kWork || kind == MessageKind::kStop;
}

// Layout (little-endian): 0 magic u32 | 4 version u16 | 6 kind u16 | 8 frameId i32 |
// 12 reserved u32 (0) | 16 payloadBytes u64 | 24 aux u64 | 32 sequence u64.
std::vector<std::byte> EncodeMessage(const MessageHeader& header,
                                     std::span<const std::byte> payload) {
  ZEPHYR_CHECK_EQ(header.payloadBytes, payload.size());
  std::vector<std::byte> message(MessageHeader::kBytes + payload.size());
  std::byte* h = message.data();
  Put<std::uint32_t>(h + 0, MessageHeader::kMagic);
  Put<std::uint16_t>(h + 4, MessageHeader::kVersion);
  Put<std::uint16_t>(h + 6, std::uint16_t(header.kind));
  Put<std::int32_t>(h + 8, header.frameId);
  Put<std::uint32_t>(h + 12, 0);
  Put<std::uint64_t>(h + 16, header.payloadBytes);
  Put<std::uint64_t>(h + 24, header.aux);
  Put<std::uint64_t>(h + 32, header.sequence);
  if (!payload.empty()) std::memcpy(h + MessageHeader::kBytes, payload.data(), payload.size());
  return message;
}

MessageHeader DecodeHeader(std::span<const std::byte> message, const std::string& sender) {
  auto bad = [&](const std::string& what) {
    return UserError("malformed message from " + sender + ": " + what);
  };
  if (message.size() < MessageHeader::kBytes)
    throw bad(std::to_string(message.size()) + " bytes, shorter than the " +
              std::to_string(MessageHeader::kBytes) + "-byte header");
  const std::byte* h = message.data();
  if (Get<std::uint32_t>(h) != MessageHeader::kMagic) throw bad("bad magic number");
  if (std::uint16_t v = Get<std::uint16_t>(h + 4); v != MessageHeader::kVersion)
    throw bad("protocol version " + std::to_string(v) + ", expected " +
              std::to_string(MessageHeader::kVersion));
  std::uint16_t kind = Get<std::uint16_t>(h + 6);
  if (kind < 1 || kind > kMessageKindCount)
    throw bad("unknown message kind " + std::to_string(kind));
  if (Get<std::uint32_t>(h + 12) != 0) throw bad("reserved header field is not 0");
  MessageHeader header;
  header.kind = MessageKind(kind);
  header.frameId = Get<std::int32_t>(h + 8);
  header.payloadBytes = Get<std::uint64_t>(h + 16);
  header.aux = Get<std::uint64_t>(h + 24);
  header.sequence = Get<std::uint64_t>(h + 32);
  if (header.payloadBytes > MessageHeader::kMaxPayload)
    throw bad("payload of " + std::to_string(header.payloadBytes) + " bytes is over the limit");
  if (header.payloadBytes != message.size() - MessageHeader::kBytes)
    throw bad("header announces " + std::to_string(header.payloadBytes) + " payload bytes but " +
              std::to_string(message.size() - MessageHeader::kBytes) + " arrived");
  return header;
}

void AppendRect(const Frame& frame, std::vector<std::byte>& out) {
  std::size_t at = out.size();
  out.resize(at + kRectBytes);
  Put<std::int32_t>(&out[at + 0], frame.x0);
  Put<std::int32_t>(&out[at + 4], frame.y0);
  Put<std::int32_t>(&out[at + 8], frame.width);
  Put<std::int32_t>(&out[at + 12], frame.height);
}

Frame ReadRect(std::span<const std::byte> payload, int frameId) {
  if (payload.size() < kRectBytes)
    throw UserError("malformed message: frame " + std::to_string(frameId) +
                    " payload has no frame rectangle");
  Frame f;
  f.id = frameId;
  f.x0 = Get<std::int32_t>(&payload[0]);
  f.y0 = Get<std::int32_t>(&payload[4]);
  f.width = Get<std::int32_t>(&payload[8]);
  f.height = Get<std::int32_t>(&payload[12]);
  return f;
}

void TrafficAccount::Add(MessageKind kind, std::uint64_t payloadBytes) {
  TrafficCount& c = counts_[int(kind) - 1];
  c.messages += 1;
  c.payloadBytes += payloadBytes;
  c.envelopeBytes += MessageHeader::kBytes;
}

TrafficCount TrafficAccount::Total() const {
  TrafficCount t;
  for (const TrafficCount& c : counts_) {
    t.messages += c.messages;
    t.payloadBytes += c.payloadBytes;
    t.envelopeBytes += c.envelopeBytes;
  }
  return t;
}

TrafficAccount& TrafficAccount::operator+=(const TrafficAccount& other) {
  for (int k = 0; k < kMessageKindCount; ++k) {
    counts_[k].messages += other.counts_[k].messages;
    counts_[k].payloadBytes += other.counts_[k].payloadBytes;
    counts_[k].envelopeBytes += other.counts_[k].envelopeBytes;
  }
  return *this;
}

namespace {
nlohmann::json CountJson(const TrafficCount& c) {
  return {{"messages", c.messages},
          {"payloadBytes", c.payloadBytes},
          {"envelopeBytes", c.envelopeBytes}};
}
}  // namespace

nlohmann::json TrafficAccount::ToJson() const {
  nlohmann::json j = nlohmann::json::object();
  for (int k = 1; k <= kMessageKindCount; ++k)
    if (counts_[k - 1].messages > 0) j[MessageKindName(MessageKind(k))] = CountJson(counts_[k - 1]);
  j["total"] = CountJson(Total());
  return j;
}

TrafficAccount TrafficAccount::FromJson(const nlohmann::json& j) {
  TrafficAccount account;
  try {
    for (int k = 1; k <= kMessageKindCount; ++k) {
      auto it = j.find(MessageKindName(MessageKind(k)));
      if (it == j.end()) continue;
      TrafficCount& c = account.counts_[k - 1];
      c.messages = it->at("messages").get<std::uint64_t>();
      c.payloadBytes = it->at("payloadBytes").get<std::uint64_t>();
      c.envelopeBytes = it->at("envelopeBytes").get<std::uint64_t>();
    }
  } catch (const nlohmann::json::exception& e) {
    throw UserError(std::string("malformed traffic counts: ") + e.what());
  }
  return account;
}

}  // namespace zephyr
