// hosts/farm/checkpoint.h — finished frames kept on disk as they arrive, so a render that
// loses a child (or the whole MPI job, or cannot write its image) can be resumed with only
// the missing frames.
//
// The file sits next to the output (`out.png` → `out.png.frames`). It starts with a header
// naming the job (image size, frame size, pixel size, and a hash of everything that decides
// the pixels: method, scene text, options), written under a temporary name and renamed into
// place (hosts/io/output_file.h); then one record per finished frame, appended with a single
// write(2). Every record stands on its own: a marker, the frame id and size with their own
// checksum, the pixels, and a checksum of id and pixels — so a damaged record (a flipped bit,
// a record torn by a crash or a full disk) is found, reported and skipped on resume while
// every intact record before and after it is kept. Resuming never cuts the file: new records
// are appended after whatever is there. A checkpoint made for another job is refused.
//
// Record (little-endian): "ZFRM", u32 frame id, u32 pixel bytes, u32 head check (low 32 bits
// of FNV-1a of the 12 bytes before it), the pixels, u64 FNV-1a of (frame id, pixels).
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

// What resuming found besides the intact frames.
struct CheckpointDamage {
  std::vector<int> badFrames;       // frame ids of records whose head is intact but whose
                                    // pixels fail their checksum or are cut short
  std::size_t unreadableBytes = 0;  // bytes in no intact record (bad records included)
  int unreadableRegions = 0;        // runs of such bytes
  bool Any() const { return unreadableBytes > 0; }
};

// Deletes a finished job's checkpoint. Call it only after every output is safely written:
// until then the checkpoint is the only copy of the rendered frames.
void RemoveCheckpoint(const std::string& path);

class FrameCheckpoint {
 public:
  // Starts a new checkpoint (replacing any old file once the new header is on disk).
  static FrameCheckpoint Create(const std::string& path, const CheckpointKey& key);
  // Opens an existing one for --resume: throws UserError if it is missing or was made for a
  // different job. Every record is checked on its own: the intact ones are in Frames() (the
  // last copy when a frame appears twice), the damaged ones in Damage(). The file is not cut;
  // new frames are appended after its end.
  static FrameCheckpoint Resume(const std::string& path, const CheckpointKey& key);

  FrameCheckpoint(FrameCheckpoint&& other) noexcept;
  FrameCheckpoint& operator=(FrameCheckpoint&&) = delete;
  ~FrameCheckpoint();

  // Appends one finished frame; it is on disk (in the kernel) when this returns. UserError
  // when the write fails (a full disk): the record may then be torn, and Resume skips it.
  void Append(int frameId, std::span<const std::byte> pixels);
  const std::map<int, std::vector<std::byte>>& Frames() const { return frames_; }
  const CheckpointDamage& Damage() const { return damage_; }
  const std::string& Path() const { return path_; }

 private:
  FrameCheckpoint(std::string path, int fd) : path_(std::move(path)), fd_(fd) {}
  std::string path_;
  int fd_ = -1;
  std::map<int, std::vector<std::byte>> frames_;  // only filled by Resume
  CheckpointDamage damage_;                       // only filled by Resume
};

}  // namespace zephyr
