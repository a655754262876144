// hosts/simd/audit.cpp — the test-only record of an object program's run (hosts/simd/audit.h).
#include "hosts/simd/audit.h"

#include <utility>

#include "fixed/check.h"

namespace zephyr::simd {

void Audit::Record(const std::string& name, const bitserial::Multi& x, std::vector<double> bound,
                   Side side) {
  const int64_t pes = x.GetMachine().VirtualPes();
  ZEPHYR_CHECK_EQ(int64_t(bound.size()), pes);
  Quantity q{name, {}, std::move(bound), side};
  q.value.reserve(pes);
  for (int64_t pe = 0; pe < pes; ++pe) q.value.push_back(x.At(pe));
  quantities.push_back(std::move(q));
}

std::vector<double> Audit::Where(const bitserial::Multi& mask, double bound, int64_t pes) {
  std::vector<double> b(pes, bound);
  if (!mask.Empty())
    for (int64_t pe = 0; pe < pes; ++pe)
      if (!mask.BitAt(0, pe)) b[pe] = kNoClaim;
  return b;
}

std::vector<double> Audit::Values(const bitserial::Multi& x) {
  const int64_t pes = x.GetMachine().VirtualPes();
  std::vector<double> v(pes);
  for (int64_t pe = 0; pe < pes; ++pe) v[pe] = fixed::ToDouble(x.At(pe));
  return v;
}

}  // namespace zephyr::simd
