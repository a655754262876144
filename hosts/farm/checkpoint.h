// hosts/farm/checkpoint.h — finished frames kept on disk as they arrive, so a render that
// loses a child (or the whole MPI job) can be resumed with only the missing frames.
//
// The file sits next to the output (`out.png` → `out.png.frames`). It starts with a header
// naming the job (image size, frame size, pixel size, and a hash of everything that decides
// the pixels: method, scene text, options); then one record per finished frame, each
// written with a single write(2) and carrying its own checksum. A record torn by a crash is
// detected and dropped on resume; a checkpoint made for another job is refused.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

namespace zephyr {

struct CheckpointKey {
  int imageWidth = 0, imageHeight = 0, frameSize = 0;
  std::uint32_t bytesPerPixel = 0;
  std::uint64_t jobHash = 0;  // FNV-1a of the job description (see JobHash)
  bool operator==(const CheckpointKey&) const = default;
};

std::uint64_t JobHash(std::span<const std::byte> bytes, std::uint64_t seed = 0xcbf29ce484222325ull);
std::uint64_t JobHash(const std::string& text, std::uint64_t seed = 0xcbf29ce484222325ull);

std::string CheckpointPathFor(const std::string& outputPath);

class FrameCheckpoint {
 public:
  // Starts a new checkpoint (replacing any old file).
  static FrameCheckpoint Create(const std::string& path, const CheckpointKey& key);
  // Opens an existing one for --resume: throws UserError if it is missing or was made for a
  // different job; a torn last record is cut off. The frames found are in Frames().
  static FrameCheckpoint Resume(const std::string& path, const CheckpointKey& key);

  FrameCheckpoint(FrameCheckpoint&& other) noexcept;
  FrameCheckpoint& operator=(FrameCheckpoint&&) = delete;
  ~FrameCheckpoint();

  // Appends one finished frame; it is on disk (in the kernel) when this returns.
  void Append(int frameId, std::span<const std::byte> pixels);
  const std::map<int, std::vector<std::byte>>& Frames() const { return frames_; }
  std::size_t DroppedBytes() const { return droppedBytes_; }  // torn tail cut on resume
  const std::string& Path() const { return path_; }
  // Closes and deletes the file (after the finished image has been written).
  void Remove();

 private:
  FrameCheckpoint(std::string path, int fd) : path_(std::move(path)), fd_(fd) {}
  std::string path_;
  int fd_ = -1;
  std::map<int, std::vector<std::byte>> frames_;  // only filled by Resume
  std::size_t droppedBytes_ = 0;
};

}  // namespace zephyr
