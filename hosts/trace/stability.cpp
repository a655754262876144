// hosts/trace/stability.cpp — the stability study of the ray–sphere test (hosts/trace/stability.h).
#include "hosts/trace/stability.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "fixed/check.h"
#include "fixed/reference.h"
#include "hosts/trace/exact.h"
#include "hosts/trace/intersect.h"

namespace zephyr::stability {

namespace {

using fixed::reference::RefReal;

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
  return {
      exact::SphereHit({c[0], c[1], c[2]}, r, {o[0], o[1], o[2]}, {d[0], d[1], d[2]}, RefReal(0)),
      false};
}

template <typename T>
Outcome FloatHit(SphereTest form, const Vec3& dir, double distance, RefReal d[3], RefReal c[3]) {
  const Vec3T<T> o(T(0), T(0), T(0)), dd(dir), centre(T(0), T(0), T(distance));
  d[0] = RefReal(dd.x), d[1] = RefReal(dd.y), d[2] = RefReal(dd.z);
  c[0] = 0, c[1] = 0, c[2] = RefReal(centre.z);
  T roots[2];
  const int n = form == SphereTest::kNaive
                    ? IntersectSphereNaive<T>(o, dd, centre, T(1), T(0), roots)
                    : IntersectSphereHearnBaker<T>(o, dd, centre, T(1), T(0), roots);
  if (n == 0) return {};
  return {RefReal(roots[0]), false};
}

// The fixed-point forms, every operation in the working format w (floor, saturate).
Outcome FixedHit(SphereTest form, fixed::Format w, const Vec3& dir, double distance, RefReal d[3],
                 RefReal c[3]) {
  using namespace fixed;
  const Policy p{Rounding::kFloor, OverflowPolicy::kSaturate};
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
  if (form == SphereTest::kNaive) {
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

Outcome Hit(const StudyFormat& f, SphereTest form, const Vec3& dir, double distance, RefReal d[3],
            RefReal c[3]) {
  switch (f.kind) {
    case StudyFormat::Kind::kFloat32:
      return FloatHit<float>(form, dir, distance, d, c);
    case StudyFormat::Kind::kFloat64:
      return FloatHit<double>(form, dir, distance, d, c);
    case StudyFormat::Kind::kFixed:
      return FixedHit(form, f.fixedFormat, dir, distance, d, c);
  }
  ZEPHYR_CHECK(false);
  return {};
}

// A count of the study outside its range: a value error (the command names its flag).
void CheckStudyRange(const char* what, int value, int lo, int hi) {
  if (value < lo || value > hi)
    throw UserError(fmt::format("stability: {} must be {}..{}, got {}", what, lo, hi, value));
}

}  // namespace

StudyFormat StudyFormat::Parse(const std::string& text) {
  if (text == "float32" || text == "float") return {Kind::kFloat32, {}, "float32"};
  if (text == "float64" || text == "double") return {Kind::kFloat64, {}, "float64"};
  const fixed::Format f = fixed::Format::Parse(text);  // throws UserError naming the text
  if (!f.isSigned) throw UserError("stability: format '" + text + "' must be signed (sN.M)");
  return {Kind::kFixed, f, f.Name()};
}

FanResult RunFan(const StudyFormat& f, SphereTest form, double distance, int rays) {
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

// distance: one row per (distance, form, format).
void WriteDistanceStudy(std::FILE* f, const std::vector<StudyFormat>& formats, int rays,
                        int maxLog2, int stepsPerOctave) {
  CheckStudyRange("rays", rays, 1, kMaxFanRays);
  CheckStudyRange("the largest distance's log2", maxLog2, 1, 60);
  CheckStudyRange("distances per octave", stepsPerOctave, 1, 1024);
  std::fprintf(f,
               "distance,form,format,rays,wrong_hit_pct,flagged_pct,silent_wrong_pct,"
               "t_relerr_max,t_relerr_median\n");
  for (int k = stepsPerOctave; k <= maxLog2 * stepsPerOctave; ++k) {
    const double distance = std::exp2(double(k) / stepsPerOctave);
    for (SphereTest form : {SphereTest::kNaive, SphereTest::kHearnBaker}) {
      for (const StudyFormat& sf : formats) {
        const FanResult r = RunFan(sf, form, distance, rays);
        std::fprintf(f, "%.9g,%s,%s,%d,%.6g,%.6g,%.6g,%.6g,%.6g\n", distance,
                     kSphereTestNames.NameOf(form), sf.name.c_str(), r.rays,
                     100.0 * r.wrongHit / r.rays, 100.0 * r.flagged / r.rays,
                     100.0 * r.silentWrong / r.rays, r.tRelErrMax, r.tRelErrMedian);
      }
    }
  }
}

// Overflow: for fixed formats s<I>.<F>, I = 2..maxIntBits, the largest distance (in
// quarter octaves) at which no ray of a small fan raises a flag, and the largest at which
// every ray is still right (hit/miss and t within 1 %). The theory: naive fails near
// D = 2^(I/2) (it squares the distance), Hearn–Baker near D = 2^I.
void WriteOverflowStudy(std::FILE* f, int fracBits, int maxIntBits, int rays) {
  CheckStudyRange("rays", rays, 1, kMaxFanRays);
  CheckStudyRange("fraction bits", fracBits, 4, 64);
  CheckStudyRange("the most integer bits", maxIntBits, 2, fixed::kMaxWidth - 1 - fracBits);
  std::fprintf(f, "int_bits,frac_bits,form,max_extent_unflagged,max_extent_correct\n");
  constexpr int kSteps = 4;
  for (int intBits = 2; intBits <= maxIntBits; ++intBits) {
    const StudyFormat sf{StudyFormat::Kind::kFixed, fixed::Format::Signed(intBits, fracBits),
                         fixed::Format::Signed(intBits, fracBits).Name()};
    for (SphereTest form : {SphereTest::kNaive, SphereTest::kHearnBaker}) {
      double unflagged = 0, correct = 0;
      bool flagSeen = false, wrongSeen = false;
      // From D = 2 r (the eye outside the sphere) to past the format's range: beyond 2^I
      // even the centre cannot be represented.
      for (int k = kSteps; k <= (intBits + 1) * kSteps && !(flagSeen && wrongSeen); ++k) {
        const double distance = std::exp2(double(k) / kSteps);
        const FanResult r = RunFan(sf, form, distance, rays);
        if (!flagSeen && r.flagged == 0)
          unflagged = distance;
        else
          flagSeen = true;
        const bool right = r.wrongHit == 0 && r.tRelErrMax <= 0.01;
        if (!wrongSeen && right)
          correct = distance;
        else
          wrongSeen = true;
      }
      std::fprintf(f, "%d,%d,%s,%.9g,%.9g\n", intBits, fracBits, kSphereTestNames.NameOf(form),
                   unflagged, correct);
    }
  }
}

}  // namespace zephyr::stability
