// The frame farm's pieces, in process: frames, the queue, the message header checks, the
// traffic account and the checkpoint file (torn records of every length and damaged ones each
// skipped on their own, the file never cut on resume, another job's checkpoint).
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "fixed/check.h"
#include "hosts/farm/checkpoint.h"
#include "hosts/farm/frame.h"
#include "hosts/farm/protocol.h"
#include "tests/farm/mpi_launch.h"

namespace zephyr {
namespace {

TEST(FrameGrid, CoversTheImageWithSmallerEdgeFrames) {
  FrameGrid grid(10, 7, 4);
  ASSERT_EQ(grid.Columns(), 3);
  ASSERT_EQ(grid.Rows(), 2);
  std::vector<int> covered(10 * 7, 0);
  for (const Frame& f : grid.All())
    for (int y = f.y0; y < f.y0 + f.height; ++y)
      for (int x = f.x0; x < f.x0 + f.width; ++x) covered[y * 10 + x]++;
  for (int c : covered) EXPECT_EQ(c, 1);
  EXPECT_EQ(grid.At(2), (Frame{2, 8, 0, 2, 4}));  // right edge: 2 wide
  EXPECT_EQ(grid.At(5), (Frame{5, 8, 4, 2, 3}));  // corner: 2×3
  EXPECT_EQ(FrameGrid(5, 5, 100).Count(), 1);     // the whole image in one frame
  EXPECT_EQ(FrameGrid(5, 5, 1).Count(), 25);
}

TEST(FrameGrid, FrameSizeZeroIsAUserError) {
  try {
    FrameGrid(8, 8, 0);
    FAIL() << "no error";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("frame size must be at least 1"), std::string::npos);
  }
}

TEST(FrameGrid, PasteAndCutAreInverse) {
  const int w = 5, h = 4;
  std::vector<std::byte> image(w * h * 2);
  for (std::size_t i = 0; i < image.size(); ++i) image[i] = std::byte(i);
  FrameGrid grid(w, h, 3);
  std::vector<std::byte> copy(image.size(), std::byte{0xEE});
  for (const Frame& f : grid.All()) PasteFrame(f, CutFrame(f, image, w, 2), copy, w, 2);
  EXPECT_EQ(copy, image);
}

TEST(FrameQueue, HandsOutInOrderAndRequeuedFramesGoFirst) {
  FrameQueue q({0, 1, 2, 3});
  EXPECT_EQ(q.Next(), 0);
  EXPECT_EQ(q.Next(), 1);
  q.Requeue(0);
  EXPECT_EQ(q.Next(), 0);
  EXPECT_EQ(q.Next(), 2);
  EXPECT_EQ(q.Size(), 1u);
}

std::vector<std::byte> Message(MessageKind kind, std::size_t payload) {
  std::vector<std::byte> p(payload, std::byte{7});
  return EncodeMessage({.kind = kind, .frameId = 3, .payloadBytes = payload, .aux = 9}, p);
}

void ExpectRejected(std::vector<std::byte> m, const std::string& why) {
  try {
    DecodeHeader(m, "rank 1");
    FAIL() << "accepted: " << why;
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
}

TEST(MessageHeader, RoundTripsAndRejectsEveryMalformation) {
  auto m = Message(MessageKind::kResult, 5);
  ASSERT_EQ(m.size(), MessageHeader::kBytes + 5);
  MessageHeader h = DecodeHeader(m, "rank 1");
  EXPECT_EQ(h.kind, MessageKind::kResult);
  EXPECT_EQ(h.frameId, 3);
  EXPECT_EQ(h.payloadBytes, 5u);
  EXPECT_EQ(h.aux, 9u);

  ExpectRejected(std::vector<std::byte>(m.begin(), m.begin() + 39), "shorter than the 40-byte");
  auto bad = m;
  bad[0] = std::byte{0};
  ExpectRejected(bad, "bad magic");
  bad = m;
  bad[4] = std::byte{2};
  ExpectRejected(bad, "protocol version 2");
  bad = m;
  bad[6] = std::byte{0};
  ExpectRejected(bad, "unknown message kind 0");
  bad = m;
  bad[6] = std::byte{8};
  ExpectRejected(bad, "unknown message kind 8");
  bad = m;
  bad.push_back(std::byte{1});  // one byte more than the header announces
  ExpectRejected(bad, "announces 5 payload bytes but 6 arrived");
  bad = m;
  bad[12] = std::byte{1};
  ExpectRejected(bad, "reserved");
}

TEST(TrafficAccount, CountsPayloadAndEnvelopeByKindAndRoundTripsJson) {
  TrafficAccount a;
  a.Add(MessageKind::kWork, 16);
  a.Add(MessageKind::kWork, 36);
  a.Add(MessageKind::kStop, 0);
  EXPECT_EQ(a.Of(MessageKind::kWork).messages, 2u);
  EXPECT_EQ(a.Of(MessageKind::kWork).payloadBytes, 52u);
  EXPECT_EQ(a.Of(MessageKind::kWork).envelopeBytes, 80u);
  EXPECT_EQ(a.Total().envelopeBytes, 120u);
  TrafficAccount b = TrafficAccount::FromJson(a.ToJson());
  EXPECT_EQ(b.ToJson(), a.ToJson());
  EXPECT_THROW(TrafficAccount::FromJson(nlohmann::json{{"work", {{"messages", "x"}}}}), UserError);
}

// Record layout (hosts/farm/checkpoint.h): 16-byte head, the pixels, an 8-byte hash; the
// file starts with a 32-byte header.
constexpr std::size_t kHeader = 32, kHead = 16, kTail = 8;

std::vector<std::byte> FramePixels(int frame) {  // 4×4 frames of 3 bytes a pixel
  std::vector<std::byte> p(4 * 4 * 3);
  for (std::size_t i = 0; i < p.size(); ++i) p[i] = std::byte(frame * 37 + i);
  return p;
}

void FlipBit(const std::string& path, std::size_t at) {
  std::string bytes = testing::ReadFile(path);
  ASSERT_LT(at, bytes.size());
  bytes[at] ^= 4;
  std::ofstream(path, std::ios::binary) << bytes;
}

TEST(FrameCheckpoint, ATornLastRecordIsSkippedAndNewFramesFollowItWithoutCuttingTheFile) {
  testing::TempDir dir;
  const std::string path = dir / "out.png.frames";
  CheckpointKey key{8, 8, 4, 3, JobHash("scene")};
  {
    FrameCheckpoint c = FrameCheckpoint::Create(path, key);
    c.Append(0, FramePixels(0));
    c.Append(3, FramePixels(3));
  }
  const auto full = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, full - 5);  // the second record torn by a crash
  {
    FrameCheckpoint c = FrameCheckpoint::Resume(path, key);
    ASSERT_EQ(c.Frames().size(), 1u);
    EXPECT_EQ(c.Frames().at(0), FramePixels(0));
    EXPECT_EQ(c.Damage().badFrames, std::vector<int>{3});  // its head is whole: frame 3
    EXPECT_EQ(c.Damage().unreadableBytes, kHead + 48 + kTail - 5);
    EXPECT_EQ(std::filesystem::file_size(path), full - 5) << "resume must not cut the file";
    c.Append(3, FramePixels(3));  // rendered again: after the torn bytes, which stay
  }
  FrameCheckpoint c = FrameCheckpoint::Resume(path, key);
  ASSERT_EQ(c.Frames().size(), 2u);
  EXPECT_EQ(c.Frames().at(3), FramePixels(3));
  EXPECT_TRUE(c.Damage().badFrames.empty()) << "frame 3 has an intact copy now";
  EXPECT_EQ(c.Damage().unreadableBytes, kHead + 48 + kTail - 5);
  EXPECT_EQ(std::filesystem::file_size(path), full - 5 + kHead + 48 + kTail);
}

// A crash tears the record being written at any byte. For every length 1..(record size) of
// the torn piece — inside the marker, the head, the pixels, the hash, and whole at the end of
// the range — after a good record: resuming keeps the good record, names the torn frame when
// its head is whole (16 bytes or more) and counts exactly the torn bytes as one unreadable
// region; the resumed run appends after them (the file is never cut), and the records it
// writes — another frame, and the torn one rendered again — are read back whole.
TEST(FrameCheckpoint, ATornRecordOfEveryLengthBeforeAGoodOneCostsOnlyItsBytes) {
  testing::TempDir dir;
  const std::string path = dir / "out.png.frames";
  CheckpointKey key{16, 16, 4, 3, JobHash("scene")};
  const std::size_t record = kHead + 48 + kTail;
  for (std::size_t torn = 1; torn <= record; ++torn) {
    const std::string what =
        "torn after " + std::to_string(torn) + " of " + std::to_string(record) + " bytes";
    {
      FrameCheckpoint c = FrameCheckpoint::Create(path, key);
      c.Append(0, FramePixels(0));
      c.Append(3, FramePixels(3));
    }
    std::filesystem::resize_file(path, kHeader + record + torn);
    const bool whole = torn == record, headWhole = torn >= kHead && !whole;
    {
      FrameCheckpoint c = FrameCheckpoint::Resume(path, key);
      EXPECT_EQ(c.Frames().size(), whole ? 2u : 1u) << what;
      EXPECT_TRUE(c.Frames().count(0) && c.Frames().at(0) == FramePixels(0)) << what;
      EXPECT_EQ(c.Damage().badFrames, headWhole ? std::vector<int>{3} : std::vector<int>{}) << what;
      EXPECT_EQ(c.Damage().unreadableBytes, whole ? 0 : torn) << what;
      c.Append(5, FramePixels(5));
      c.Append(3, FramePixels(3));
    }
    EXPECT_EQ(std::filesystem::file_size(path), kHeader + record + torn + 2 * record)
        << what << ": cut";
    FrameCheckpoint c = FrameCheckpoint::Resume(path, key);
    EXPECT_EQ(c.Frames().size(), 3u) << what;
    for (const int id : {0, 3, 5}) {
      EXPECT_TRUE(c.Frames().count(id) && c.Frames().at(id) == FramePixels(id))
          << what << ", frame " << id;
    }
    EXPECT_TRUE(c.Damage().badFrames.empty()) << what << ": frame 3 has an intact copy";
    EXPECT_EQ(c.Damage().unreadableBytes, whole ? 0 : torn) << what;
    EXPECT_EQ(c.Damage().unreadableRegions, whole ? 0 : 1) << what;
  }
}

// One flipped bit costs exactly the record it is in, wherever it is: the pixels (the frame
// is named), the head (the frame is unknown, its bytes are skipped) or the hash.
TEST(FrameCheckpoint, EveryRecordIsCheckedOnItsOwn) {
  testing::TempDir dir;
  const std::string path = dir / "out.png.frames";
  CheckpointKey key{16, 16, 4, 3, JobHash("scene")};
  const std::size_t record = kHead + 48 + kTail;
  const struct {
    std::size_t offset;  // within record 1
    bool frameKnown;
  } flips[] = {{kHead + 10, true}, {5, false}, {kHead + 48 + 3, true}, {0, false}};
  for (const auto& flip : flips) {
    {
      FrameCheckpoint c = FrameCheckpoint::Create(path, key);
      for (int id = 0; id < 16; ++id) c.Append(id, FramePixels(id));
    }
    const auto size = std::filesystem::file_size(path);
    FlipBit(path, kHeader + record + flip.offset);
    FrameCheckpoint c = FrameCheckpoint::Resume(path, key);
    EXPECT_EQ(c.Frames().size(), 15u) << "flip at " << flip.offset;
    EXPECT_EQ(c.Frames().count(1), 0u);
    for (int id = 0; id < 16; ++id)
      if (id != 1) {
        EXPECT_EQ(c.Frames().at(id), FramePixels(id)) << id;
      }
    EXPECT_EQ(c.Damage().badFrames, flip.frameKnown ? std::vector<int>{1} : std::vector<int>{});
    EXPECT_EQ(c.Damage().unreadableBytes, record);
    EXPECT_EQ(c.Damage().unreadableRegions, 1);
    EXPECT_EQ(std::filesystem::file_size(path), size);
  }
}

TEST(FrameCheckpoint, RefusesAnotherJobsCheckpointAndAMissingOne) {
  testing::TempDir dir;
  const std::string path = dir / "out.png.frames";
  CheckpointKey key{8, 8, 4, 3, JobHash("scene")};
  FrameCheckpoint::Create(path, key).Append(0, std::vector<std::byte>(48));
  CheckpointKey other = key;
  other.jobHash = JobHash("another scene");
  EXPECT_THROW(FrameCheckpoint::Resume(path, other), UserError);
  other = key;
  other.frameSize = 2;
  EXPECT_THROW(FrameCheckpoint::Resume(path, other), UserError);
  EXPECT_THROW(FrameCheckpoint::Resume(dir / "missing.frames", key), UserError);
  // Create replaces an old checkpoint only with a whole new header.
  FrameCheckpoint::Create(path, key);
  EXPECT_EQ(std::filesystem::file_size(path), kHeader);
  EXPECT_EQ(FrameCheckpoint::Resume(path, key).Frames().size(), 0u);
}

}  // namespace
}  // namespace zephyr
