// hosts/simd/options.cpp — the names of the SIMD pass's options and the profile they choose.
#include "hosts/simd/options.h"

#include "fixed/check.h"

namespace zephyr::simd {

UncertainPolicy ParseUncertainPolicy(const std::string& name) {
  if (name == "recompute") return UncertainPolicy::kRecompute;
  if (name == "keep") return UncertainPolicy::kKeep;
  if (name == "fail") return UncertainPolicy::kFail;
  if (name == "refine") return UncertainPolicy::kRefine;
  if (name == "auto") return UncertainPolicy::kAuto;
  throw UserError("--uncertain: expected auto, recompute, refine, keep or fail, got '" + name + "'");
}
const char* UncertainPolicyName(UncertainPolicy p) {
  switch (p) {
    case UncertainPolicy::kRecompute: return "recompute";
    case UncertainPolicy::kRefine: return "refine";
    case UncertainPolicy::kKeep: return "keep";
    case UncertainPolicy::kFail: return "fail";
    case UncertainPolicy::kAuto: return "auto";
  }
  return "?";
}

NumberSystem ParseNumberSystem(const std::string& name) {
  if (name == "fixed") return NumberSystem::kFixed;
  if (name == "float") return NumberSystem::kFloat;
  throw UserError("--number: expected fixed or float, got '" + name + "'");
}
const char* NumberSystemName(NumberSystem n) { return n == NumberSystem::kFloat ? "float" : "fixed"; }

bitserial::MachineProfile MachineProfileOf(const SimdOptions& o) {
  bitserial::MachineProfile p = bitserial::Profile(o.profile);
  for (const std::string& a : o.profileOverrides) p.Override(a);
  return p;
}

}  // namespace zephyr::simd
