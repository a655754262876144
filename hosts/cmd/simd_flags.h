// hosts/cmd/simd_flags.h — the SIMD primary pass's flags, declared once and shared by
// `zephyr render`, `zephyr plan` and `zephyr accuracy` (docs/simd.md, "The planner").
//
//   SimdFlags flags;
//   flags.AddTo(*cmd, "simd: ");            // --frac-bits --dir-frac-bits --int-bits
//                                           // --number --float-format
//                                           // [--uncertain] --machine --set --threads
//   simd::SimdOptions o = flags.Options();  // in the command's callback
#pragma once

#include <string>
#include <vector>

#include "hosts/simd/pass.h"

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace zephyr {

class SimdFlags {
 public:
  // Adds the flags to `command`; `helpPrefix` starts each help line (render says "simd: ",
  // as its flags serve several methods). --uncertain only when `withUncertain` (`plan`
  // prints formats and has no pixels to be uncertain about).
  void AddTo(CLI::App& command, const std::string& helpPrefix, bool withUncertain = true);
  // The options the flags give (the defaults where none was given; --uncertain auto).
  // UserError for an unknown --machine, a bad --float-format or one without --number float.
  // The widths (simd::kMinFracBits..kMaxFracBits, ...), --threads (0..bitserial::kMaxThreads),
  // --number and --uncertain are checked as the command line is parsed (flags.h).
  simd::SimdOptions Options() const;
  // The names of the flags given on the command line ("--frac-bits", ...).
  std::vector<std::string> Given() const;

 private:
  simd::SimdOptions options_;
  std::string floatFormat_;
  std::vector<CLI::Option*> added_;
};

}  // namespace zephyr
