// hosts/cmd/stability.cpp — `zephyr stability`: where the ray–sphere test fails
// (docs/background.md, "Precision, accuracy, speed"; docs/results.md, "Where methods fail").
//
//   zephyr stability distance --out FILE.csv   error against distance for a small, far sphere
//   zephyr stability overflow --out FILE.csv   largest scene extent each fixed format holds
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
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "fixed/check.h"
#include "fixed/format.h"
#include "fixed/reference.h"
#include "hosts/io/output_file.h"
#include "hosts/cmd/command.h"
#include "hosts/cmd/flags.h"
#include "hosts/scene/geometry.h"
#include "hosts/trace/exact.h"
#include "hosts/trace/intersect.h"

namespace zephyr {
namespace {

using fixed::reference::RefReal;

// A number format of the study: float32, float64, or a fixed format such as s15.16.
struct StudyFormat {
  enum class Kind { kFloat32, kFloat64, kFixed } kind;
  fixed::Format fixedFormat;
  std::string name;

  static StudyFormat Parse(const std::string& text) {
    if (text == "float32" || text == "float") return {Kind::kFloat32, {}, "float32"};
    if (text == "float64" || text == "double") return {Kind::kFloat64, {}, "float64"};
    const fixed::Format f = fixed::Format::Parse(text);  // throws UserError naming the text
    if (!f.isSigned) throw UserError("stability: format '" + text + "' must be signed (sN.M)");
    return {Kind::kFixed, f, f.Name()};
  }
};

enum class Form { kNaive, kHearnBaker };
const char* FormName(Form f) { return f == Form::kNaive ? "naive" : "hb"; }

// One ray of the fan: the eye at the origin, direction (unit, in double).
struct FanRay {
  Vec3 direction;
};

// `count` rays toward the plane through the centre at closest-approach 0 .. 1.25 r, turning
// by the golden angle so no component is exactly zero.
std::vector<FanRay> MakeFan(double distance, int count) {
  std::vector<FanRay> fan;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double p = 1.25 * (i + 0.5) / count;
    const double a = golden * i;
    fan.push_back({Normalize(Vec3(p * std::cos(a), p * std::sin(a), distance))});
  }
  return fan;
}

// The outcome of one test: the nearest t > 0, if any, and whether a fixed flag was raised.
struct Outcome {
  std::optional<RefReal> t;
  bool flagged = false;
};

// The exact nearest root t > 0 for the given (already rounded) inputs: the exact
// reference's sphere (hosts/trace/exact.h).
Outcome ExactHit(const RefReal o[3], const RefReal d[3], const RefReal c[3], const RefReal& r) {
  return {exact::SphereHit({c[0], c[1], c[2]}, r, {o[0], o[1], o[2]}, {d[0], d[1], d[2]}, RefReal(0)), false};
}

template <typename T>
Outcome FloatHit(Form form, const Vec3& dir, double distance, RefReal d[3], RefReal c[3]) {
  const Vec3T<T> o(T(0), T(0), T(0)), dd(dir), centre(T(0), T(0), T(distance));
  d[0] = RefReal(dd.x), d[1] = RefReal(dd.y), d[2] = RefReal(dd.z);
  c[0] = 0, c[1] = 0, c[2] = RefReal(centre.z);
  T roots[2];
  const int n = form == Form::kNaive ? IntersectSphereNaive<T>(o, dd, centre, T(1), T(0), roots)
                                     : IntersectSphereHearnBaker<T>(o, dd, centre, T(1), T(0), roots);
  if (n == 0) return {};
  return {RefReal(roots[0]), false};
}

// The fixed-point forms, every operation in the working format w (floor, saturate).
Outcome FixedHit(Form form, fixed::Format w, const Vec3& dir, double distance, RefReal d[3],
                 RefReal c[3]) {
  using namespace fixed;
  const Policy p{Rounding::Floor, OverflowPolicy::Saturate};
  Status st;
  const Fixed dx = FromDouble(dir.x, w, p, &st), dy = FromDouble(dir.y, w, p, &st),
              dz = FromDouble(dir.z, w, p, &st);
  const Fixed cz = FromDouble(distance, w, p, &st);
  const Fixed one = FromDouble(1.0, w, p, &st);
  d[0] = RefReal(reference::ExactValue(dx)), d[1] = RefReal(reference::ExactValue(dy));
  d[2] = RefReal(reference::ExactValue(dz));
  c[0] = 0, c[1] = 0, c[2] = RefReal(reference::ExactValue(cz));
  const Fixed zero = FromDouble(0.0, w, p, &st);
  // f = o − c = (0, 0, −cz); b = −f·d = cz·dz.
  const Fixed fz = Neg(cz, w, p, &st);
  const Fixed b = Mul(cz, dz, w, p, &st);
  Fixed disc;
  if (form == Form::kNaive) {
    const Fixed ff = Mul(fz, fz, w, p, &st);  // |f|²: D², the square that overflows
    const Fixed cc = Sub(ff, one, w, p, &st);
    disc = Sub(Mul(b, b, w, p, &st), cc, w, p, &st);
  } else {
    const Fixed vx = Mul(dx, b, w, p, &st), vy = Mul(dy, b, w, p, &st);
    const Fixed vz = Add(fz, Mul(dz, b, w, p, &st), w, p, &st);
    Fixed vv = Mul(vx, vx, w, p, &st);
    vv = Add(vv, Mul(vy, vy, w, p, &st), w, p, &st);
    vv = Add(vv, Mul(vz, vz, w, p, &st), w, p, &st);
    disc = Sub(one, vv, w, p, &st);
  }
  if (Compare(disc, zero) < 0) return {std::nullopt, st.Any()};
  const Fixed s = Sqrt(disc, w, p, &st);
  Fixed t = Sub(b, s, w, p, &st);
  if (Compare(t, zero) <= 0) t = Add(b, s, w, p, &st);
  if (Compare(t, zero) <= 0) return {std::nullopt, st.Any()};
  return {RefReal(reference::ExactValue(t)), st.Any()};
}

Outcome Hit(const StudyFormat& f, Form form, const Vec3& dir, double distance, RefReal d[3],
            RefReal c[3]) {
  switch (f.kind) {
    case StudyFormat::Kind::kFloat32: return FloatHit<float>(form, dir, distance, d, c);
    case StudyFormat::Kind::kFloat64: return FloatHit<double>(form, dir, distance, d, c);
    case StudyFormat::Kind::kFixed: return FixedHit(form, f.fixedFormat, dir, distance, d, c);
  }
  ZEPHYR_CHECK(false);
  return {};
}

// What one (distance, form, format) cell measured over the fan.
struct FanResult {
  int rays = 0;
  int wrongHit = 0;      // hit where the exact test misses, or the reverse
  int flagged = 0;       // fixed: some operation overflowed (detected)
  int silentWrong = 0;   // wrong (hit/miss or t off by > 1 %) with no flag raised
  double tRelErrMax = 0, tRelErrMedian = 0;  // over rays both call a hit
};

FanResult RunFan(const StudyFormat& f, Form form, double distance, int rays) {
  static const RefReal kZero[3] = {0, 0, 0};
  FanResult r;
  std::vector<double> errors;
  for (const FanRay& ray : MakeFan(distance, rays)) {
    RefReal d[3], c[3];
    const Outcome got = Hit(f, form, ray.direction, distance, d, c);
    const Outcome exact = ExactHit(kZero, d, c, RefReal(1));
    ++r.rays;
    if (got.flagged) ++r.flagged;
    bool wrong = false;
    if (got.t.has_value() != exact.t.has_value()) {
      ++r.wrongHit;
      wrong = true;
    } else if (got.t) {
      const double e = double(abs(*got.t - *exact.t) / *exact.t);
      errors.push_back(e);
      wrong = e > 0.01;
    }
    if (wrong && !got.flagged) ++r.silentWrong;
  }
  if (!errors.empty()) {
    std::sort(errors.begin(), errors.end());
    r.tRelErrMax = errors.back();
    r.tRelErrMedian = errors[errors.size() / 2];
  }
  return r;
}

// A CSV on standard output ("-") or written atomically to a file (hosts/io/output_file.h);
// the file's temporary is created up front, so a bad path fails before the study runs.
class CsvOut {
 public:
  explicit CsvOut(const std::string& path) {
    if (path != "-") file_.emplace(path, "CSV file");
  }
  std::FILE* Stream() const { return file_ ? file_->Stream() : stdout; }
  void Commit() {
    if (file_) return file_->Commit();
    if (std::fflush(stdout) != 0) throw UserError("cannot write the CSV to standard output");
  }

 private:
  std::optional<OutputFile> file_;
};

std::vector<StudyFormat> ParseFormats(const std::vector<std::string>& names) {
  std::vector<StudyFormat> formats;
  for (const std::string& n : names) formats.push_back(StudyFormat::Parse(n));
  return formats;
}

// distance: one row per (distance, form, format).
void RunDistance(const std::string& out, const std::vector<std::string>& formatNames,
                 int rays, int maxLog2, int stepsPerOctave) {
  if (rays < 1) throw UserError("stability distance: --rays must be at least 1");
  if (maxLog2 < 1 || maxLog2 > 60) throw UserError("stability distance: --max-log2 must be in 1..60");
  if (stepsPerOctave < 1) throw UserError("stability distance: --steps must be at least 1");
  const std::vector<StudyFormat> formats = ParseFormats(formatNames);
  CsvOut csv(out);
  std::FILE* f = csv.Stream();
  std::fprintf(f, "distance,form,format,rays,wrong_hit_pct,flagged_pct,silent_wrong_pct,"
                  "t_relerr_max,t_relerr_median\n");
  for (int k = stepsPerOctave; k <= maxLog2 * stepsPerOctave; ++k) {
    const double distance = std::exp2(double(k) / stepsPerOctave);
    for (Form form : {Form::kNaive, Form::kHearnBaker}) {
      for (const StudyFormat& sf : formats) {
        const FanResult r = RunFan(sf, form, distance, rays);
        std::fprintf(f, "%.9g,%s,%s,%d,%.6g,%.6g,%.6g,%.6g,%.6g\n", distance, FormName(form),
                     sf.name.c_str(), r.rays, 100.0 * r.wrongHit / r.rays,
                     100.0 * r.flagged / r.rays, 100.0 * r.silentWrong / r.rays, r.tRelErrMax,
                     r.tRelErrMedian);
      }
    }
  }
  csv.Commit();
}

// overflow: for fixed formats s<I>.<F>, I = 2..maxIntBits, the largest distance (in
// quarter octaves) at which no ray of a small fan raises a flag, and the largest at which
// every ray is still right (hit/miss and t within 1 %). The theory: naive fails near
// D = 2^(I/2) (it squares the distance), Hearn–Baker near D = 2^I.
void RunOverflow(const std::string& out, int fracBits, int maxIntBits, int rays) {
  if (fracBits < 4 || fracBits > 64) throw UserError("stability overflow: --frac-bits must be in 4..64");
  if (maxIntBits < 2 || maxIntBits + fracBits + 1 > fixed::kMaxWidth)
    throw UserError("stability overflow: --max-int-bits must be at least 2 and fit 128 bits");
  CsvOut csv(out);
  std::FILE* f = csv.Stream();
  std::fprintf(f, "int_bits,frac_bits,form,max_extent_unflagged,max_extent_correct\n");
  constexpr int kSteps = 4;
  for (int intBits = 2; intBits <= maxIntBits; ++intBits) {
    const StudyFormat sf{StudyFormat::Kind::kFixed, fixed::Format::Signed(intBits, fracBits),
                         fixed::Format::Signed(intBits, fracBits).Name()};
    for (Form form : {Form::kNaive, Form::kHearnBaker}) {
      double unflagged = 0, correct = 0;
      bool flagSeen = false, wrongSeen = false;
      // From D = 2 r (the eye outside the sphere) to past the format's range: beyond 2^I
      // even the centre cannot be represented.
      for (int k = kSteps; k <= (intBits + 1) * kSteps && !(flagSeen && wrongSeen); ++k) {
        const double distance = std::exp2(double(k) / kSteps);
        const FanResult r = RunFan(sf, form, distance, rays);
        if (!flagSeen && r.flagged == 0) unflagged = distance; else flagSeen = true;
        const bool right = r.wrongHit == 0 && r.tRelErrMax <= 0.01;
        if (!wrongSeen && right) correct = distance; else wrongSeen = true;
      }
      std::fprintf(f, "%d,%d,%s,%.9g,%.9g\n", intBits, fracBits, FormName(form), unflagged,
                   correct);
    }
  }
  csv.Commit();
}

CommandRegistration reg("stability", [](CLI::App& program) {
  auto* cmd = program.add_subcommand(
      "stability", "Where the ray-sphere test fails: error vs distance, overflow vs extent (CSV)");
  cmd->require_subcommand(1);

  struct Args {
    std::string out = "-";
    std::vector<std::string> formats = {"float32", "float64", "s15.16", "s23.24", "s31.32"};
    int rays = 256, maxLog2 = 24, steps = 2, fracBits = 16, maxIntBits = 32, overflowRays = 16;
  };
  auto a = std::make_shared<Args>();

  auto* dist = cmd->add_subcommand(
      "distance", "Error against distance: a radius-1 sphere at D = 2^(k/steps), naive vs Hearn-Baker");
  dist->add_option("--out", a->out, "CSV file ('-' = standard output)")->capture_default_str();
  dist->add_option("--formats", a->formats, "Formats: float32, float64, sI.F (fixed)")
      ->delimiter(',')->capture_default_str();
  AddInteger(*dist, "--rays", a->rays, 1, 1 << 20, "Rays in the fan (closest approach 0..1.25 r)");
  AddInteger(*dist, "--max-log2", a->maxLog2, 1, 60, "Largest distance 2^N");
  AddInteger(*dist, "--steps", a->steps, 1, 1024, "Distances per octave");
  dist->callback([a] {
    CheckOutputs({{"--out", a->out}});
    RunDistance(a->out, a->formats, a->rays, a->maxLog2, a->steps);
  });

  auto* over = cmd->add_subcommand(
      "overflow", "Largest scene extent each fixed format sI.F holds, naive vs Hearn-Baker");
  over->add_option("--out", a->out, "CSV file ('-' = standard output)")->capture_default_str();
  AddInteger(*over, "--frac-bits", a->fracBits, 4, 64, "Fraction bits F");
  AddInteger(*over, "--max-int-bits", a->maxIntBits, 2, fixed::kMaxWidth, "Integer bits I from 2 to this (I + F + 1 within 128)");
  AddInteger(*over, "--rays", a->overflowRays, 1, 1 << 20, "Rays in the fan");
  over->callback([a] {
    CheckOutputs({{"--out", a->out}});
    RunOverflow(a->out, a->fracBits, a->maxIntBits, a->overflowRays);
  });
});

}  // namespace
}  // namespace zephyr
