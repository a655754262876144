#include "bitserial/machine.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>

#include "fixed/check.h"

namespace zephyr::bitserial {

namespace {
int LayersFor(const MachineProfile& p, int64_t virtualPes) {
  if (virtualPes < 0) throw UserError(fmt::format("virtual PEs must be >= 0, got {}", virtualPes));
  int64_t v = virtualPes == 0 ? p.physicalPes : virtualPes;
  return static_cast<int>((v + p.physicalPes - 1) / p.physicalPes);
}

LayerBlock CheckBlock(LayerBlock b, int layers) {
  if (b.count == 0 && b.first == 0) return {0, layers};
  if (b.count == 0) b.count = layers - b.first;
  if (b.first < 0 || b.count < 1 || b.first + b.count > layers)
    throw UserError(fmt::format("layer block {}..{} is outside the machine's {} layer(s)", b.first,
                                b.first + b.count - 1, layers));
  return b;
}
}  // namespace

Machine::Machine(MachineProfile profile, int64_t virtualPes, int shapeIndex, LayerBlock block)
    : profile_(std::move(profile)),
      modelledPes_(virtualPes == 0 ? profile_.physicalPes : virtualPes),
      modelledLayers_(LayersFor(profile_, virtualPes)),
      firstLayer_(CheckBlock(block, modelledLayers_).first),
      layers_(CheckBlock(block, modelledLayers_).count),
      firstPe_(int64_t{firstLayer_} * profile_.physicalPes),
      virtualPes_(
          std::min<int64_t>(modelledPes_ - firstPe_, int64_t{layers_} * profile_.physicalPes)),
      wordsPerLayer_(profile_.physicalPes / 64),
      words_(layers_ * wordsPerLayer_),
      memory_(profile_.internalBitsPerPe, profile_.externalBitsPerPe, modelledLayers_),
      report_(&profile_, modelledLayers_),
      kernels_(&bitserial::Kernels()) {
  if (shapeIndex < 0 || shapeIndex >= static_cast<int>(profile_.shapes.size()))
    throw UserError(fmt::format("profile '{}' has {} mesh shape(s); shape {} does not exist",
                                profile_.name, profile_.shapes.size(), shapeIndex));
  shape_ = profile_.shapes[shapeIndex];
  ZEPHYR_CHECK_EQ(shape_.Size(), profile_.physicalPes);
  zero_ = AcquirePlanes(1);
  std::memset(zero_, 0, words_ * sizeof(Word));
  ones_ = AcquirePlanes(1);
  std::memset(ones_, 0xff, words_ * sizeof(Word));
  overflow_ = AcquirePlanes(1);
  divideByZero_ = AcquirePlanes(1);
  invalid_ = AcquirePlanes(1);
  ClearFlags();
  Word* base = AcquirePlanes(1);  // the PEs that exist
  for (size_t w = 0; w < words_; ++w) {
    int64_t first = static_cast<int64_t>(w) * 64;
    int64_t n = std::clamp<int64_t>(virtualPes_ - first, 0, 64);
    base[w] = n == 64 ? ~Word{0} : ((Word{1} << n) - 1);
  }
  activity_.push_back(base);
}

Machine::~Machine() = default;

std::vector<Word> Machine::SaveOverflow() const {
  return std::vector<Word>(overflow_, overflow_ + words_);
}

void Machine::RestoreOverflow(const std::vector<Word>& saved) {
  ZEPHYR_CHECK(saved.size() == words_);
  std::copy(saved.begin(), saved.end(), overflow_);
}

void Machine::ClearFlags() {
  for (Word* f : {overflow_, divideByZero_, invalid_}) std::memset(f, 0, words_ * sizeof(Word));
}

Word* Machine::AcquirePlanes(int planes) {
  ZEPHYR_CHECK_GE(planes, 1);
  auto& list = free_[planes];
  if (!list.empty()) {
    Word* p = list.back();
    list.pop_back();
    return p;
  }
  const size_t words = static_cast<size_t>(planes) * PlaneStride();
  auto block = hwy::AllocateAligned<Word>(words);
  // Host memory for the emulated PEs' bit-planes ran out (a 2^24-PE machine under a small
  // `ulimit -v`): a clear error, not a null plane (docs/errors.md, "Memory").
  if (!block)
    throw UserError(fmt::format(
        "the emulated array cannot get {:.3f} MiB of host memory for {} bit-plane(s) of {} "
        "PEs: the machine or the program is too large for this process's memory limit "
        "(ulimit -v)",
        double(words * sizeof(Word)) / (1 << 20), planes, int64_t(words_) * 64));
  blocks_.push_back(std::move(block));
  return blocks_.back().get();
}

void Machine::ReleasePlanes(Word* p, int planes) {
  if (p) free_[planes].push_back(p);
}

void Machine::PushActivity(const Word* mask, bool complement) {
  Word* next = AcquirePlanes(1);
  kernels_->logic(complement ? LogicOp::kAndNot : LogicOp::kAnd, activity_.back(), mask, next,
                  words_);
  activity_.push_back(next);
}

void Machine::PopActivity() {
  ZEPHYR_CHECK_GE(activity_.size(), 2u);
  ReleasePlanes(activity_.back(), 1);
  activity_.pop_back();
}

const Word* Machine::MeshEdgeMask(int axis, int distance) {
  auto key = std::make_pair(axis, distance);
  auto it = edgeMasks_.find(key);
  if (it != edgeMasks_.end()) return it->second;
  Word* m = AcquirePlanes(1);
  std::memset(m, 0, words_ * sizeof(Word));
  const int pes = profile_.physicalPes;
  int stride = 1;
  for (int a = 0; a < axis; ++a) stride *= shape_.extent[a];
  const int extent = shape_.extent[axis];
  for (int layer = 0; layer < layers_; ++layer)
    for (int pe = 0; pe < pes; ++pe) {
      int coord = (pe / stride) % extent - distance;
      if (coord >= 0 && coord < extent) {
        int64_t bit = static_cast<int64_t>(layer) * pes + pe;
        m[bit >> 6] |= Word{1} << (bit & 63);
      }
    }
  edgeMasks_[key] = m;
  return m;
}

}  // namespace zephyr::bitserial
