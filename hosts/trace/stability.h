// hosts/trace/stability.h — where the ray–sphere test fails (docs/background.md, "Precision,
// accuracy, speed"; docs/results.md, "Where methods fail"): the study behind `zephyr
// stability` (hosts/cmd/stability.cpp holds its flags and output file).
//
// The Ray Tracing Gems ch. 7 case: a sphere of radius 1 at distance D straight ahead of the
// eye, hit by a fan of rays whose closest approach to the centre runs from 0 to 1.25 radii
// (so the fan holds hits, misses and grazing rays). Each number format sees the inputs
// rounded to that format; the exact reference (hosts/trace/exact.h) solves the same
// (rounded) ray with 128-bit floats, so what is measured is the formula's loss, not the
// rounding of the inputs. Float formats use the tracer's own routines (hosts/trace/intersect.h);
// fixed formats compute the same two forms with fixed/'s datapath arithmetic, which the
// bit-serial array reproduces bit for bit (tests/bitserial/arith_test.cpp):
//   naive        c = |f|² − r², disc = b² − c, t = b − √disc   (needs integer bits for D²)
//   Hearn–Baker  v = f + b·d,  disc = r² − |v|², t = b − √disc (integer bits for D only)
// with f = o − centre and b = −f·d. In fixed point the near root b − √disc has only absolute
// rounding error, so the fixed Hearn–Baker form needs no |f|² at all. Every fixed
// operation saturates and raises a flag; flagged rays are counted, never silent.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "fixed/format.h"
#include "hosts/trace/tracer.h"

namespace zephyr::stability {

// A number format of the study: float32, float64, or a fixed format such as s15.16.
struct StudyFormat {
  enum class Kind { kFloat32, kFloat64, kFixed } kind;
  fixed::Format fixedFormat;
  std::string name;
  // "float32" (or "float"), "float64" (or "double"), or a signed fixed format sI.F;
  // UserError otherwise.
  static StudyFormat Parse(const std::string& text);
};

// The most rays a fan may have.
inline constexpr int kMaxFanRays = 1 << 20;

// What one (distance, form, format) cell measured over the fan.
struct FanResult {
  int rays = 0;
  int wrongHit = 0;     // hit where the exact test misses, or the reverse
  int flagged = 0;      // fixed: some operation overflowed (detected)
  int silentWrong = 0;  // wrong (hit/miss or t off by > 1 %) with no flag raised
  double tRelErrMax = 0, tRelErrMedian = 0;  // over rays both call a hit
};

// The fan of `rays` rays at a radius-1 sphere `distance` ahead, in one format and form.
FanResult RunFan(const StudyFormat& f, SphereTest form, double distance, int rays);

// Distance: one CSV row per (distance, form, format), D = 2^(k/stepsPerOctave) for k up to
// maxLog2·stepsPerOctave. UserError for a count outside its range (rays 1..kMaxFanRays,
// maxLog2 1..60, stepsPerOctave 1..1024).
void WriteDistanceStudy(std::FILE* out, const std::vector<StudyFormat>& formats, int rays,
                        int maxLog2, int stepsPerOctave);
// Overflow: per fixed format s<I>.<F>, I = 2..maxIntBits, the largest extent each form holds
// unflagged and correct (one CSV row per I and form). UserError for fracBits outside 4..64 or
// a format wider than the 128 bits of fixed/.
void WriteOverflowStudy(std::FILE* out, int fracBits, int maxIntBits, int rays);

}  // namespace zephyr::stability
