// bitserial/machine.h — the emulated PE array: geometry, virtual-PE layers, PE memory,
// activity, per-PE flags, the plane pool and the cycle report.
//
// Storage: one plane is WordsPerPlane() words = Layers() × (physical PEs / 64): all layers
// side by side, so every kernel runs an instruction for every layer at once while the
// report charges each layer its cycles. Virtual PE v lives in layer v / physicalPes at PE
// v % physicalPes, i.e. simply bit v of a plane. Planes come from a pool owned by the
// machine and are reused, so a program's steady state allocates nothing per operation;
// the host holds only planes of variables that exist.
//
// A machine may also hold only a block of another machine's layers (LayerBlock): it models
// the whole machine (its PE memory is split over every layer, its report charges every
// layer) but stores and computes only its own layers, so a program without reductions runs
// block by block, each block's planes staying in cache (bitserial/blocks.h).
#pragma once

#include <hwy/aligned_allocator.h>

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bitserial/cost.h"
#include "bitserial/kernels.h"
#include "bitserial/memory.h"
#include "bitserial/profile.h"
#include "bitserial/report.h"

namespace zephyr::bitserial {

// Layers [first, first + count) of a machine (count >= 1; count = 0 means up to the last).
struct LayerBlock {
  int first = 0;
  int count = 0;
};

class Machine {
 public:
  // virtualPes = 0 means one per physical PE; shapeIndex picks profile.shapes[i]. With a
  // block, the machine holds only those layers of the virtualPes-PE machine (UserError if
  // the block is outside it).
  explicit Machine(MachineProfile profile, int64_t virtualPes = 0, int shapeIndex = 0,
                   LayerBlock block = {});
  ~Machine();
  Machine(const Machine&) = delete;
  Machine& operator=(const Machine&) = delete;

  const MachineProfile& Profile() const { return profile_; }
  const MeshShape& Shape() const { return shape_; }
  // The virtual PEs and layers this machine holds (a block's own), the first one's index
  // in the whole machine, and the whole machine's (modelled) PEs and layers, by which the
  // memory is split and the report multiplies.
  int64_t VirtualPes() const { return virtualPes_; }
  int Layers() const { return layers_; }
  int64_t FirstPe() const { return firstPe_; }
  int FirstLayer() const { return firstLayer_; }
  int64_t ModelledPes() const { return modelledPes_; }
  int ModelledLayers() const { return modelledLayers_; }
  bool IsBlock() const { return layers_ != modelledLayers_; }
  size_t WordsPerLayer() const { return wordsPerLayer_; }
  size_t WordsPerPlane() const { return words_; }
  // Words from one plane to the next in a block of AcquirePlanes(n > 1) planes (a Multi's
  // bits): WordsPerPlane() plus kPlanePadWords unused words. Without the pad, planes 1, 2,
  // 4 or 8 KiB apart (1, 2, 4, 8 layers) fall into the same few L1/L2 cache sets and a
  // kernel that reads one vector of each of ~40 planes per step misses every time
  // (docs/bitserial.md, "Speed"). Host layout only: no PE, result, flag or cycle depends on it.
  size_t PlaneStride() const { return words_ + kPlanePadWords; }
  static constexpr size_t kPlanePadWords = 16;  // two 64-byte cache lines
  PeMemory& Memory() { return memory_; }
  CycleReport& Report() { return report_; }
  const PlaneKernels& Kernels() const { return *kernels_; }

  // Charges one operation (counts are per layer; the report multiplies by the layers).
  void Charge(const std::string& op, const MicroOpCounts& counts) { report_.Charge(op, counts); }
  // Charges counts summed over every layer (an operation whose layers differ).
  void ChargeWhole(const std::string& op, const MicroOpCounts& total) {
    report_.ChargeWhole(op, total);
  }

  // The current activity plane: existing virtual PEs inside every enclosing where.
  const Word* Activity() const { return activity_.back(); }
  bool AllActive() const { return activity_.size() == 1; }
  // where: activity &= mask (or &= ~mask with complement); PopActivity restores.
  void PushActivity(const Word* mask, bool complement);
  void PopActivity();

  // Sticky per-PE flags, set only where active (fixed::Status per virtual PE): overflow,
  // divideByZero (Div) and invalid (Sqrt of a negative value). Only the Multi operations
  // (bitserial/multi.cpp) write them; a program reads them per PE here.
  bool Overflow(int64_t pe) const { return (overflow_[pe >> 6] >> (pe & 63)) & 1; }
  bool DivideByZero(int64_t pe) const { return (divideByZero_[pe >> 6] >> (pe & 63)) & 1; }
  bool Invalid(int64_t pe) const { return (invalid_[pe >> 6] >> (pe & 63)) & 1; }
  void ClearFlags();  // all three

  // The overflow flags of every virtual PE (WordsPerPlane() words, bit v = PE v), and their
  // restoration: a program part whose saturation is expected (a clamp meaning "no hit")
  // saves them before and restores them after, so it marks no PE. Host-side bookkeeping:
  // the caller charges the flag operations it models.
  std::vector<Word> SaveOverflow() const;
  void RestoreOverflow(const std::vector<Word>& saved);

  const Word* ZeroPlane() const { return zero_; }
  const Word* OnesPlane() const { return ones_; }

  // Pooled plane storage: `planes` planes of WordsPerPlane() words, PlaneStride() words
  // apart, 64-byte aligned.
  Word* AcquirePlanes(int planes);
  void ReleasePlanes(Word* p, int planes);

  // The plane whose bit is 1 where coordinate `axis` minus `distance` is inside the mesh
  // (the PEs that receive a value in a mesh shift); cached.
  const Word* MeshEdgeMask(int axis, int distance);

 private:
  // bitserial/multi.cpp: the writable flag planes and the reusable pointer arrays that
  // build kernel arguments (no allocation per op).
  friend struct MachineInternals;

  MachineProfile profile_;
  MeshShape shape_;
  int64_t modelledPes_;
  int modelledLayers_;
  int firstLayer_;
  int layers_;
  int64_t firstPe_;
  int64_t virtualPes_;
  size_t wordsPerLayer_;
  size_t words_;
  PeMemory memory_;
  CycleReport report_;
  const PlaneKernels* kernels_;
  std::vector<hwy::AlignedFreeUniquePtr<Word[]>> blocks_;
  std::map<int, std::vector<Word*>> free_;
  std::vector<Word*> activity_;
  Word* overflow_;
  Word* divideByZero_;
  Word* invalid_;
  Word* zero_;
  Word* ones_;
  std::map<std::pair<int, int>, Word*> edgeMasks_;
  std::vector<const Word*> ptrA_, ptrB_;
  std::vector<Word*> ptrOut_;
};

}  // namespace zephyr::bitserial
