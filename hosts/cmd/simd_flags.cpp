#include "hosts/cmd/simd_flags.h"

#include <CLI/CLI.hpp>
#include <string>

#include "bitserial/blocks.h"
#include "bitserial/profile.h"
#include "fixed/check.h"
#include "hosts/cmd/flags.h"

namespace zephyr {

void SimdFlags::AddTo(CLI::App& command, const std::string& helpPrefix, bool withUncertain) {
  // The widths' ranges: the narrowest at which the pass's error bounds are tested and the
  // widest it supports (hosts/simd/plan.h).
  auto bits = [&](const char* name, int& value, int lo, int hi, const char* help) {
    added_.push_back(AddInteger(command, name, value, lo, hi, helpPrefix + help,
                                "the SIMD pass's error bounds are tested from " +
                                    std::to_string(lo) + " bits and it supports up to " +
                                    std::to_string(hi) + ", docs/simd.md"));
  };
  bits("--frac-bits", options_.formats.fracBits, simd::kMinFracBits, simd::kMaxFracBits,
       "fraction bits of lengths, t and directions (default: planned per scene)");
  bits("--dir-frac-bits", options_.formats.dirFracBits, simd::kMinFracBits, simd::kMaxDirFracBits,
       "fraction bits of the directions only");
  bits("--int-bits", options_.formats.intBits, simd::kMinIntBits, simd::kMaxIntBits,
       "integer bits of distances");
  added_.push_back(AddNamed(
      command, "--number", options_.number, simd::kNumberSystemNames,
      helpPrefix + "number system of the ray-object intersections on the array: fixed or float "
                   "(bit-serial floating point; spheres only, docs/simd.md)"));
  added_.push_back(command.add_option(
      "--float-format", floatFormat_,
      helpPrefix +
          "with --number float: the format, eXmY[ftz] as in docs/float.md (e8m23 = binary32; "
          "default: planned per scene)"));
  options_.uncertain = simd::UncertainPolicy::kAuto;  // the command line's default (docs/simd.md)
  if (withUncertain)
    added_.push_back(AddNamed(
        command, "--uncertain", options_.uncertain, simd::kUncertainPolicyNames,
        helpPrefix + "uncertain pixels: auto (refine where the first pass flags more than 1 % of "
                     "the pixels, else recompute), recompute (in double on the host), refine (a "
                     "second, wider "
                     "array pass on them first), keep, fail"));
  added_.push_back(command.add_option(
      "--machine", options_.profile,
      helpPrefix + "machine profile: a built-in name (wavetracer, mpp, blitzen; zephyr "
                   "profile list) or a profile file (docs/bitserial.md)"));
  added_.push_back(command.add_option(
      "--set", options_.profileOverrides,
      helpPrefix + "override an entry of the machine profile, NAME=VALUE (e.g. "
                   "--set clockHz=20e6; as zephyr cycles --set, docs/bitserial.md)"));
  added_.push_back(AddInteger(
      command, "--threads", options_.threads, 0, bitserial::kMaxThreads,
      helpPrefix + "host threads emulating the array and recomputing uncertain "
                   "pixels (default or 0: every core; the results do not depend on it)"));
}

simd::SimdOptions SimdFlags::Options() const {
  simd::SimdOptions o = options_;
  // The widths, --threads, --number and --uncertain were checked as the command line was
  // parsed (flags.h).
  if (!floatFormat_.empty()) {
    if (o.number != simd::NumberSystem::kFloat)
      throw UserError("--float-format " + floatFormat_ + " applies to --number float only");
    o.floatFormat = fixed::FloatFormat::Parse(floatFormat_);
  }
  if (o.threads != 0) bitserial::CheckThreads(o.threads);  // 0: not given, every core
  simd::ResolveMachine(o);  // an unknown --machine before any work (UserError naming the known ones)
  return o;
}

std::vector<std::string> SimdFlags::Given() const {
  std::vector<std::string> names;
  for (const CLI::Option* option : added_)
    if (option->count() > 0) names.push_back(option->get_name());
  return names;
}

}  // namespace zephyr
