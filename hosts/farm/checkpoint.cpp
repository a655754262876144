#include "hosts/farm/checkpoint.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "fixed/check.h"

namespace zephyr {

namespace {
constexpr char kMagic[8] = {'Z', 'P', 'H', 'C', 'K', 'P', 'T', '1'};
constexpr std::size_t kHeaderBytes = 8 + 4 * 4 + 8;  // magic, w, h, F, bpp, hash
constexpr std::size_t kRecordHeadBytes = 4 + 4;      // frame id, pixel bytes; then pixels, hash

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

FrameCheckpoint FrameCheckpoint::Create(const std::string& path, const CheckpointKey& key) {
  int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw UserError("cannot create checkpoint " + path + ": " + std::strerror(errno));
  FrameCheckpoint checkpoint(path, fd);
  WriteAll(fd, HeaderBytes(key), path);
  return checkpoint;
}

FrameCheckpoint FrameCheckpoint::Resume(const std::string& path, const CheckpointKey& key) {
  int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
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
    throw UserError(path + ": not a zephyr frame checkpoint");
  if (std::memcmp(bytes.data(), expected.data(), kHeaderBytes) != 0)
    throw UserError(path +
                    ": checkpoint was made for a different job (scene, method, image, "
                    "frame size or options differ); delete it or run without --resume");
  const std::size_t framePixelsMax = std::size_t(key.frameSize) * key.frameSize * key.bytesPerPixel;
  std::size_t at = kHeaderBytes;
  while (at < bytes.size()) {
    if (bytes.size() - at < kRecordHeadBytes) break;
    std::uint32_t frameId = GetU32(&bytes[at]);
    std::uint32_t size = GetU32(&bytes[at + 4]);
    if (size > framePixelsMax || bytes.size() - at - kRecordHeadBytes < std::size_t(size) + 8)
      break;
    std::span<const std::byte> pixels(&bytes[at + kRecordHeadBytes], size);
    if (GetU64(&bytes[at + kRecordHeadBytes + size]) != RecordHash(frameId, pixels)) break;
    checkpoint.frames_[int(frameId)].assign(pixels.begin(), pixels.end());
    at += kRecordHeadBytes + size + 8;
  }
  checkpoint.droppedBytes_ = bytes.size() - at;
  if (::ftruncate(fd, off_t(at)) != 0 || ::lseek(fd, off_t(at), SEEK_SET) < 0)
    throw UserError("cannot cut torn tail of checkpoint " + path + ": " + std::strerror(errno));
  return checkpoint;
}

FrameCheckpoint::FrameCheckpoint(FrameCheckpoint&& other) noexcept
    : path_(std::move(other.path_)),
      fd_(other.fd_),
      frames_(std::move(other.frames_)),
      droppedBytes_(other.droppedBytes_) {
  other.fd_ = -1;
}

FrameCheckpoint::~FrameCheckpoint() {
  if (fd_ >= 0) ::close(fd_);
}

void FrameCheckpoint::Append(int frameId, std::span<const std::byte> pixels) {
  ZEPHYR_CHECK(fd_ >= 0);
  std::vector<std::byte> record;
  record.reserve(kRecordHeadBytes + pixels.size() + 8);
  PutU32(record, std::uint32_t(frameId));
  PutU32(record, std::uint32_t(pixels.size()));
  record.insert(record.end(), pixels.begin(), pixels.end());
  PutU64(record, RecordHash(std::uint32_t(frameId), pixels));
  WriteAll(fd_, record, path_);
}

void FrameCheckpoint::Remove() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  ::unlink(path_.c_str());
}

}  // namespace zephyr
