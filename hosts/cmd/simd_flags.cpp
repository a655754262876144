#include "hosts/cmd/simd_flags.h"

#include <CLI/CLI.hpp>
#include <string>

#include "bitserial/blocks.h"
#include "fixed/check.h"

namespace zephyr {

void SimdFlags::AddTo(CLI::App& command, const std::string& helpPrefix, bool withUncertain) {
  auto bits = [&](const char* name, int& value, const char* help) {
    added_.push_back(command.add_option(name, value, helpPrefix + help)
                         ->check(CLI::NonNegativeNumber)
                         ->option_text("UINT"));
  };
  bits("--frac-bits", options_.formats.fracBits,
       "fraction bits of lengths, t and directions (default: planned per scene)");
  bits("--dir-frac-bits", options_.formats.dirFracBits, "fraction bits of the directions only");
  bits("--int-bits", options_.formats.intBits, "integer bits of distances");
  added_.push_back(command.add_option(
      "--number", number_,
      helpPrefix + "number system of the ray-object intersections on the array: fixed (default) or float "
                   "(bit-serial floating point; spheres only, docs/simd.md)"));
  added_.push_back(command.add_option(
      "--float-format", floatFormat_,
      helpPrefix + "with --number float: the format, eXmY[ftz] as in docs/float.md (e8m23 = binary32; "
                   "default: planned per scene)"));
  if (withUncertain)
    added_.push_back(command.add_option(
        "--uncertain", uncertain_,
        helpPrefix + "uncertain pixels: auto (default: refine where the first pass flags more than 1 % of "
                     "the pixels, else recompute), recompute (in double on the host), refine (a second, wider "
                     "array pass on them first), keep, fail"));
  added_.push_back(command.add_option("--machine", options_.profile,
                                      helpPrefix + "machine profile (wavetracer, mpp)"));
  added_.push_back(command.add_option("--threads", options_.threads,
                                      helpPrefix + "host threads emulating the array and recomputing uncertain "
                                                   "pixels (default or 0: every core; the results do not depend on it)")
                       ->option_text("N"));
}

simd::SimdOptions SimdFlags::Options() const {
  simd::SimdOptions o = options_;
  // A width given below what the error bounds are tested at (docs/simd.md) is refused here,
  // before any work; unset widths (-1) are the planner's choice.
  auto atLeast = [](const char* flag, int value, int minimum, const char* unit) {
    if (value >= 0 && value < minimum)
      throw UserError(std::string(flag) + " " + std::to_string(value) + ": the SIMD pass needs at least " +
                      std::to_string(minimum) + " " + unit +
                      " (the narrowest width its error bounds are tested at, docs/simd.md)");
  };
  atLeast("--frac-bits", o.formats.fracBits, simd::kMinFracBits, "fraction bits");
  atLeast("--dir-frac-bits", o.formats.dirFracBits, simd::kMinFracBits, "direction fraction bits");
  atLeast("--int-bits", o.formats.intBits, simd::kMinIntBits, "integer bits");
  if (!number_.empty()) o.number = simd::ParseNumberSystem(number_);
  if (!floatFormat_.empty()) {
    if (o.number != simd::NumberSystem::kFloat)
      throw UserError("--float-format " + floatFormat_ + " applies to --number float only");
    o.floatFormat = fixed::FloatFormat::Parse(floatFormat_);
  }
  o.uncertain = simd::ParseUncertainPolicy(uncertain_.empty() ? "auto" : uncertain_);
  if (o.threads != 0) bitserial::CheckThreads(o.threads);  // 0: not given, every core
  return o;
}

std::vector<std::string> SimdFlags::Given() const {
  std::vector<std::string> names;
  for (const CLI::Option* option : added_)
    if (option->count() > 0) names.push_back(option->get_name());
  return names;
}

}  // namespace zephyr
