// bitserial/transfer.cpp — moving a multi between the host and the array (bitserial/multi.h):
// Load, LoadRaw, Read, ReadRaw and At; each transfer is charged one hostPlane micro-op per
// bit-plane (cost.h, HostTransferCost), the cycle report's host class.
#include <fmt/format.h>

#include <cstring>

#include "bitserial/multi.h"
#include "fixed/check.h"

namespace zephyr::bitserial {

namespace {

// Transposes a 64x64 bit matrix in place: bit c of a[r] becomes bit r of a[c] (recursive
// block swaps, Warren, Hacker's Delight, 2nd ed., section 7-3).
void Transpose64(uint64_t a[64]) {
  uint64_t m = 0x00000000FFFFFFFFull;
  for (int j = 32; j != 0; j >>= 1, m ^= m << j) {
    for (int k = 0; k < 64; k = ((k | j) + 1) & ~j) {
      const uint64_t t = ((a[k] >> j) ^ a[k | j]) & m;
      a[k | j] ^= t;
      a[k] ^= t << j;
    }
  }
}

}  // namespace

void Multi::LoadRaw(const std::vector<int64_t>& raw) {
  Machine& m = *machine_;
  if (static_cast<int64_t>(raw.size()) > m.VirtualPes())
    throw UserError(fmt::format("multi '{}': {} values for {} virtual PEs", alloc_.name, raw.size(),
                                m.VirtualPes()));
  m.Charge("hostLoad", HostTransferCost(Width()));
  std::memset(planes_, 0, sizeof(Word) * Width() * m.PlaneStride());
  // 64 PEs at a time: their values as the rows of a 64x64 bit matrix, transposed into one
  // word of each plane (bits past 64 repeat bit 63, the sign, if signed; else 0).
  const size_t count = raw.size();
  for (size_t base = 0; base < count; base += 64) {
    uint64_t block[64] = {};
    for (size_t j = 0; j < 64 && base + j < count; ++j)
      block[j] = static_cast<uint64_t>(raw[base + j]);
    Transpose64(block);
    for (int i = 0; i < Width(); ++i)
      Plane(i)[base >> 6] = i < 64 ? block[i] : (format_.isSigned ? block[63] : 0);
  }
}

void Multi::Load(const std::vector<fixed::Fixed>& values) {
  Machine& m = *machine_;
  if (static_cast<int64_t>(values.size()) > m.VirtualPes())
    throw UserError(fmt::format("multi '{}': {} values for {} virtual PEs", alloc_.name,
                                values.size(), m.VirtualPes()));
  m.Charge("hostLoad", HostTransferCost(Width()));
  std::memset(planes_, 0, sizeof(Word) * Width() * m.PlaneStride());
  for (size_t pe = 0; pe < values.size(); ++pe) {
    if (values[pe].format != format_)
      throw UserError(fmt::format("multi '{}' has format {}; value {} has {}", alloc_.name,
                                  format_.Name(), pe, values[pe].format.Name()));
    fixed::BigInt bits = values[pe].Bits();
    for (int i = 0; i < Width(); ++i)
      if (boost::multiprecision::bit_test(bits, i)) Plane(i)[pe >> 6] |= Word{1} << (pe & 63);
  }
}

fixed::Fixed Multi::At(int64_t pe) const {
  fixed::BigInt bits = 0;
  for (int i = 0; i < Width(); ++i)
    if (BitAt(i, pe)) boost::multiprecision::bit_set(bits, i);
  return fixed::Fixed::FromBits(format_, bits);
}

std::vector<fixed::Fixed> Multi::Read() const {
  machine_->Charge("hostRead", HostTransferCost(Width()));
  std::vector<fixed::Fixed> v;
  v.reserve(machine_->VirtualPes());
  for (int64_t pe = 0; pe < machine_->VirtualPes(); ++pe) v.push_back(At(pe));
  return v;
}

std::vector<int64_t> Multi::ReadRaw() const {
  ZEPHYR_CHECK_LE(Width(), 64);
  machine_->Charge("hostRead", HostTransferCost(Width()));
  const int64_t pes = machine_->VirtualPes();
  std::vector<int64_t> v(pes);
  const int w = Width();
  // 64 PEs at a time: one word of each plane as the rows of a 64x64 bit matrix, transposed
  // into the PEs' values.
  for (int64_t base = 0; base < pes; base += 64) {
    uint64_t block[64] = {};
    for (int i = 0; i < w; ++i) block[i] = Plane(i)[base >> 6];
    Transpose64(block);
    for (int64_t j = 0; j < 64 && base + j < pes; ++j) {
      uint64_t bits = block[j];
      if (format_.isSigned && w < 64 && ((bits >> (w - 1)) & 1)) bits |= ~uint64_t{0} << w;
      v[base + j] = static_cast<int64_t>(bits);
    }
  }
  return v;
}

}  // namespace zephyr::bitserial
