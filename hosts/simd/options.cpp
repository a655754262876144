// hosts/simd/options.cpp — the machine profile the SIMD pass's options choose.
#include "hosts/simd/options.h"

#include "fixed/check.h"

namespace zephyr::simd {

namespace {

// What a resolved profile was made from: the name or file, then each override in order.
std::string ResolvedFrom(const SimdOptions& o) {
  std::string key = o.profile;
  for (const std::string& a : o.profileOverrides) key += '\n' + a;
  return key;
}

bitserial::MachineProfile Resolve(const SimdOptions& o) {
  bitserial::MachineProfile p = bitserial::Profile(o.profile);
  for (const std::string& a : o.profileOverrides) p.Override(a);
  return p;
}

}  // namespace

void ResolveMachine(SimdOptions& o) {
  std::string from = ResolvedFrom(o);
  if (o.machine && o.machineResolvedFrom == from) return;
  o.machine = std::make_shared<const bitserial::MachineProfile>(Resolve(o));
  o.machineResolvedFrom = std::move(from);
}

bitserial::MachineProfile MachineProfileOf(const SimdOptions& o) {
  if (o.machine && o.machineResolvedFrom == ResolvedFrom(o)) return *o.machine;
  return Resolve(o);
}

}  // namespace zephyr::simd
