// hosts/simd/audit.h — a test-only record of one object program's run (docs/simd.md, "Error
// bounds", the audit): every quantity the program computes with the error bound it claims for
// it at each PE, read from the PEs without charge (Multi::At), so that
// tests/simd/bounds_audit_test.cpp can compare both with the exact (128-bit) reference. A
// program records only when ObjectProgram::Run is given an Audit; the pass gives none, so its
// cycles, memory and results do not depend on this.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "bitserial/multi.h"
#include "fixed/format.h"

namespace zephyr::simd {

class Audit {
 public:
  // Which side the claim bounds: |value − exact| <= bound, or only value − exact <= bound (a
  // lower bound on where the exact value lies: an uncertain candidate's tLow).
  enum class Side { kBoth, kAbove };
  struct Quantity {
    std::string name;                 // e.g. "tca", "disc", "root", "t", "margin Q/A"
    std::vector<fixed::Fixed> value;  // per PE, as computed
    std::vector<double> bound;        // per PE, the claimed bound; NaN where nothing is claimed
    Side side = Side::kBoth;
  };
  static constexpr double kNoClaim = std::numeric_limits<double>::quiet_NaN();

  // Records x at every PE with the bound claimed per PE (bound.size() == x's PEs).
  void Record(const std::string& name, const bitserial::Multi& x, std::vector<double> bound,
              Side side = Side::kBoth);
  // The per-PE bound `bound` where the 1-bit `mask` is 1 (every PE when it is empty), no claim
  // elsewhere.
  static std::vector<double> Where(const bitserial::Multi& mask, double bound, int64_t pes);
  // x's value at each PE as a double (host side, not charged).
  static std::vector<double> Values(const bitserial::Multi& x);
  static bool Claimed(double bound) { return !std::isnan(bound); }

  std::vector<Quantity> quantities;
  // Host constants the audit's exact side needs (a grazing band, a clamp's range, a
  // divisor's threshold), by name.
  std::map<std::string, double> constants;
};

}  // namespace zephyr::simd
