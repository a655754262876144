// hosts/simd/options.cpp — the machine profile the SIMD pass's options choose.
#include "hosts/simd/options.h"

#include "fixed/check.h"

namespace zephyr::simd {

bitserial::MachineProfile MachineProfileOf(const SimdOptions& o) {
  bitserial::MachineProfile p = bitserial::Profile(o.profile);
  for (const std::string& a : o.profileOverrides) p.Override(a);
  return p;
}

}  // namespace zephyr::simd
