// hosts/simd/options.h — the SIMD primary pass's options (docs/simd.md, "The planner" and
// "Uncertain pixels"): the uncertain-pixel policies, the number system, the width limits a
// user may ask for, the machine profile with its overrides. hosts/cmd/simd_flags.h fills them
// from the command line; the planner (plan.h) plans for them.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bitserial/profile.h"
#include "fixed/float.h"
#include "fixed/named.h"
#include "hosts/trace/tracer.h"

namespace zephyr::simd {

// What to do with uncertain pixels (overflow, grazing, near tie): recompute them on the host
// in double; refine them first in a second, wider array pass and recompute only what is
// still uncertain; keep the array's answer (flagged); fail; or auto: refine where the first
// pass flags more than kAutoRefineShare of the pixels, else recompute (the command line's
// default, docs/simd.md "Refine pass": the refine pass costs ~a fifth of the first pass's
// cycles whatever it refines, and below that share recompute already meets the 1 % budget).
enum class UncertainPolicy { kRecompute, kKeep, kFail, kRefine, kAuto };
inline constexpr NamedValues<UncertainPolicy, 5> kUncertainPolicyNames{
    {{{UncertainPolicy::kAuto, "auto"},
      {UncertainPolicy::kRecompute, "recompute"},
      {UncertainPolicy::kRefine, "refine"},
      {UncertainPolicy::kKeep, "keep"},
      {UncertainPolicy::kFail, "fail"}}}};
constexpr double kAutoRefineShare =
    0.01;  // the host's budget of pixels (docs/simd.md, "Refine pass")

// The narrowest widths a user may ask for (--frac-bits, --dir-frac-bits, --int-bits): the
// narrowest at which the pass's error bounds are tested (docs/simd.md, "Error bounds":
// RecomputeRepairsEveryPixelAtLowWidths from 4 fraction bits; SimdPrimary's overflow case
// with 2 integer bits). Narrower ones are refused as the flags are parsed (hosts/cmd/flags.h).
// Between these and the planner's choice most pixels are uncertain; they are flagged, counted in
// the report and recomputed unless --uncertain keep.
constexpr int kMinFracBits = 4;
constexpr int kMinIntBits = 2;
// The widest the pass supports (docs/simd.md, "The planner"): t, lengths and the matrix's
// direction fit the host's 64-bit readout with these (PlanFormats refuses wider plans).
constexpr int kMaxFracBits = 56;
constexpr int kMaxDirFracBits = 60;
constexpr int kMaxIntBits = 40;

// User overrides of the planner (negative = the planner chooses).
struct FormatOverrides {
  int fracBits = -1;     // --frac-bits: fraction bits of lengths, t and directions
  int dirFracBits = -1;  // --dir-frac-bits: fraction bits of the direction components only
  int intBits = -1;      // --int-bits: integer bits of distances
};

// The number system of the ray–object intersections (--number): fixed point, or bit-serial
// floating point (bitserial/float.h) in one format for the whole pass (docs/simd.md,
// "Floating point on the array"). The matrix and the closest-hit fold stay fixed point.
enum class NumberSystem { kFixed, kFloat };
inline constexpr NamedValues<NumberSystem, 2> kNumberSystemNames{
    {{{NumberSystem::kFixed, "fixed"}, {NumberSystem::kFloat, "float"}}}};

struct SimdOptions {
  std::string profile = "wavetracer";
  NumberSystem number = NumberSystem::kFixed;
  // --float-format (with --number float): the intersections' format; empty = planned per
  // scene (PlanFloatFormat).
  std::optional<fixed::FloatFormat> floatFormat;
  std::vector<std::string>
      profileOverrides;  // --set: "readExternal=3", ... (MachineProfile::Override)
  FormatOverrides formats;
  UncertainPolicy uncertain = UncertainPolicy::kRecompute;
  // Host threads (--threads) for the array's layer blocks and the host recompute of
  // uncertain pixels; 0 = every core. Results and reports do not depend on it.
  int threads = 0;
  // Virtual-PE layers the emulator runs the whole program on at a time
  // (bitserial/blocks.h); 0 = bitserial::DefaultBlockLayers(), at least the pass's layers =
  // op by op over the whole machine. Results and reports do not depend on it.
  int blockLayers = 0;
  // How the host recompute of uncertain pixels finds the nearest object (the render's
  // --accel, RunRender copies it here): the same hits either way.
  Accel hostAccel = Accel::kNone;
  // `profile` with `profileOverrides` applied, resolved once (ResolveMachine: the command
  // line's SimdFlags::Options() and RunRender call it) and shared by every copy of the
  // options; null until then. What it was resolved from is kept beside it, so a profile or
  // an override changed afterwards is never priced with the old one (MachineProfileOf).
  std::shared_ptr<const bitserial::MachineProfile> machine;
  std::string machineResolvedFrom;
};

// Resolves `profile` and `profileOverrides` into `options.machine` (a file is read, a name
// looked up, each override applied: UserError on a bad one). Nothing to do when they have
// not changed since the last call.
void ResolveMachine(SimdOptions& options);

// The machine profile the options name, with their overrides: `options.machine` when it was
// resolved from them, else resolved now (a caller that never called ResolveMachine; UserError
// on a bad one).
bitserial::MachineProfile MachineProfileOf(const SimdOptions& options);

}  // namespace zephyr::simd
