#include "hosts/farm/checkpoint.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "fixed/check.h"
#include "hosts/io/output_file.h"

namespace zephyr {

namespace {
// Version 2: records with a marker and a head check (version 1's records could not be
// checked one by one; its files are refused as another format).
constexpr char kMagic[8] = {'Z', 'P', 'H', 'C', 'K', 'P', 'T', '2'};
constexpr char kRecordMarker[4] = {'Z', 'F', 'R', 'M'};
constexpr std::size_t kHeaderBytes = 8 + 4 * 4 + 8;  // magic, w, h, F, bpp, hash
// marker, frame id, pixel bytes, head check; then the pixels and their u64 hash
constexpr std::size_t kRecordHeadBytes = 4 + 4 + 4 + 4;

void PutU32(std::vector<std::byte>& out, std::uint32_t v) {
  std::byte b[4];
  std::memcpy(b, &v, 4);
  out.insert(out.end(), b, b + 4);
}
void PutU64(std::vector<std::byte>& out, std::uint64_t v) {
  std::byte b[8];
  std::memcpy(b, &v, 8);
  out.insert(out.end(), b, b + 8);
}
std::uint32_t GetU32(const std::byte* p) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
std::uint64_t GetU64(const std::byte* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

std::vector<std::byte> HeaderBytes(const CheckpointKey& key) {
  std::vector<std::byte> h(reinterpret_cast<const std::byte*>(kMagic),
                           reinterpret_cast<const std::byte*>(kMagic) + 8);
  PutU32(h, std::uint32_t(key.imageWidth));
  PutU32(h, std::uint32_t(key.imageHeight));
  PutU32(h, std::uint32_t(key.frameSize));
  PutU32(h, key.bytesPerPixel);
  PutU64(h, key.jobHash);
  return h;
}

void WriteAll(int fd, std::span<const std::byte> bytes, const std::string& path) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw UserError("cannot write checkpoint " + path + ": " + std::strerror(errno));
    done += std::size_t(n);
  }
}

std::uint32_t HeadCheck(const std::byte* head) {  // over marker, frame id, pixel bytes
  return std::uint32_t(JobHash(std::span<const std::byte>(head, 12)));
}

std::uint64_t RecordHash(std::uint32_t frameId, std::span<const std::byte> pixels) {
  std::byte id[4];
  std::memcpy(id, &frameId, 4);
  return JobHash(pixels, JobHash(std::span<const std::byte>(id, 4)));
}
}  // namespace

std::uint64_t JobHash(std::span<const std::byte> bytes, std::uint64_t seed) {
  std::uint64_t h = seed;
  for (std::byte b : bytes) {
    h ^= std::uint64_t(b);
    h *= 0x100000001b3ull;
  }
  return h;
}
std::uint64_t JobHash(const std::string& text, std::uint64_t seed) {
  return JobHash(std::as_bytes(std::span(text.data(), text.size())), seed);
}

std::string CheckpointPathFor(const std::string& outputPath) { return outputPath + ".frames"; }

void RemoveCheckpoint(const std::string& path) { ::unlink(path.c_str()); }

FrameCheckpoint FrameCheckpoint::Create(const std::string& path, const CheckpointKey& key) {
  // The header goes in under a temporary name, so `path` is never a headerless file and an
  // old checkpoint is replaced only once the new one exists.
  const std::vector<std::byte> header = HeaderBytes(key);
  WriteOutputFile(path, "checkpoint",
                  std::string_view(reinterpret_cast<const char*>(header.data()), header.size()));
  int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd < 0) throw UserError("cannot open checkpoint " + path + ": " + std::strerror(errno));
  return FrameCheckpoint(path, fd);
}

FrameCheckpoint FrameCheckpoint::Resume(const std::string& path, const CheckpointKey& key) {
  int fd = ::open(path.c_str(), O_RDWR | O_APPEND | O_CLOEXEC);
  if (fd < 0)
    throw UserError("nothing to resume: cannot open checkpoint " + path + ": " +
                    std::strerror(errno));
  FrameCheckpoint checkpoint(path, fd);
  std::vector<std::byte> bytes;
  std::byte buffer[1 << 16];
  for (;;) {
    ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw UserError("cannot read checkpoint " + path + ": " + std::strerror(errno));
    if (n == 0) break;
    bytes.insert(bytes.end(), buffer, buffer + n);
  }
  std::vector<std::byte> expected = HeaderBytes(key);
  if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, 8) != 0)
    throw UserError(path + ": not a zephyr frame checkpoint (version 2)");
  if (std::memcmp(bytes.data(), expected.data(), kHeaderBytes) != 0)
    throw UserError(path +
                    ": checkpoint was made for a different job (scene, method, image, "
                    "frame size or options differ); delete it or run without --resume");
  const std::size_t framePixelsMax = std::size_t(key.frameSize) * key.frameSize * key.bytesPerPixel;
  const std::byte* marker = reinterpret_cast<const std::byte*>(kRecordMarker);
  // The next place at or after `from` where a record could start.
  auto nextMarker = [&](std::size_t from) {
    auto it = std::search(bytes.begin() + std::ptrdiff_t(std::min(from, bytes.size())), bytes.end(),
                          marker, marker + 4);
    return std::size_t(it - bytes.begin());
  };
  CheckpointDamage& damage = checkpoint.damage_;
  std::size_t at = kHeaderBytes, badFrom = 0;
  bool inBad = false;
  auto endBad = [&](std::size_t to) {
    if (!inBad) return;
    damage.unreadableBytes += to - badFrom;
    ++damage.unreadableRegions;
    inBad = false;
  };
  while (at < bytes.size()) {
    const std::size_t left = bytes.size() - at;
    if (left >= kRecordHeadBytes && std::memcmp(&bytes[at], marker, 4) == 0 &&
        GetU32(&bytes[at + 12]) == HeadCheck(&bytes[at])) {
      const std::uint32_t frameId = GetU32(&bytes[at + 4]);
      const std::uint32_t size = GetU32(&bytes[at + 8]);
      const bool fits = size <= framePixelsMax && left - kRecordHeadBytes >= std::size_t(size) + 8;
      if (fits) {
        std::span<const std::byte> pixels(&bytes[at + kRecordHeadBytes], size);
        if (GetU64(&bytes[at + kRecordHeadBytes + size]) == RecordHash(frameId, pixels)) {
          endBad(at);
          checkpoint.frames_[int(frameId)].assign(pixels.begin(), pixels.end());
          at += kRecordHeadBytes + size + 8;
          continue;
        }
      }
      // An intact head with bad or missing pixels: the frame is known, its bytes are not.
      damage.badFrames.push_back(int(frameId));
    }
    if (!inBad) badFrom = at, inBad = true;
    at = nextMarker(at + 1);  // a torn record may be followed by whole ones: look for them
  }
  endBad(bytes.size());
  // A frame whose bad record was followed by an intact copy (rendered again by an earlier
  // resume) is not missing.
  std::erase_if(damage.badFrames, [&](int id) { return checkpoint.frames_.count(id) > 0; });
  std::sort(damage.badFrames.begin(), damage.badFrames.end());
  damage.badFrames.erase(std::unique(damage.badFrames.begin(), damage.badFrames.end()),
                         damage.badFrames.end());
  return checkpoint;
}

FrameCheckpoint::FrameCheckpoint(FrameCheckpoint&& other) noexcept
    : path_(std::move(other.path_)),
      fd_(other.fd_),
      frames_(std::move(other.frames_)),
      damage_(std::move(other.damage_)) {
  other.fd_ = -1;
}

FrameCheckpoint::~FrameCheckpoint() {
  if (fd_ >= 0) ::close(fd_);
}

void FrameCheckpoint::Append(int frameId, std::span<const std::byte> pixels) {
  ZEPHYR_CHECK(fd_ >= 0);
  std::vector<std::byte> record;
  record.reserve(kRecordHeadBytes + pixels.size() + 8);
  record.insert(record.end(), reinterpret_cast<const std::byte*>(kRecordMarker),
                reinterpret_cast<const std::byte*>(kRecordMarker) + 4);
  PutU32(record, std::uint32_t(frameId));
  PutU32(record, std::uint32_t(pixels.size()));
  PutU32(record, HeadCheck(record.data()));
  record.insert(record.end(), pixels.begin(), pixels.end());
  PutU64(record, RecordHash(std::uint32_t(frameId), pixels));
  WriteAll(fd_, record, path_);
}

}  // namespace zephyr
