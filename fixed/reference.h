// fixed/reference.h — the exact reference for fixed/format.h, computed a second way.
//
// Where fixed/format.cpp shifts and adds integers as a datapath would, this computes each
// operation's exact real result as a Boost.Multiprecision rational (cpp_rational), then
// rounds it (floor, or floor(x + 1/2)) and fits it into the result format by the
// definition of the range. Tests compare the two on every operation. It also provides
// ≥100-bit binary floats (RefReal) for quantities that are not rational, such as the exact
// ray–sphere hit distance used later.
#pragma once

#include <boost/multiprecision/cpp_bin_float.hpp>
#include <boost/multiprecision/cpp_int.hpp>

#include "fixed/format.h"

namespace zephyr::fixed::reference {

using Rational = boost::multiprecision::cpp_rational;
// 128 significand bits: comfortably past the 100 the accuracy study asks for.
using RefReal = boost::multiprecision::number<boost::multiprecision::cpp_bin_float<128>>;

Rational ExactValue(const Fixed& v);
// Round an exact value to `out` and fit it; the definition of steps 2 and 3.
Fixed FromExact(const Rational& x, Format out, Policy p, Status* status);

Fixed Add(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status);
Fixed Sub(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status);
Fixed Neg(const Fixed& a, Format out, Policy p, Status* status);
Fixed Abs(const Fixed& a, Format out, Policy p, Status* status);
Fixed Min(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status);
Fixed Max(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status);
Fixed Mul(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status);
Fixed Div(const Fixed& a, const Fixed& b, Format out, Policy p, Status* status);
Fixed Sqrt(const Fixed& a, Format out, Policy p, Status* status);
Fixed Shift(const Fixed& a, int k, Format out, Policy p, Status* status);
Fixed Convert(const Fixed& a, Format out, Policy p, Status* status);
int Compare(const Fixed& a, const Fixed& b);
Fixed FromDouble(double x, Format out, Policy p, Status* status);
double ToDouble(const Fixed& v);

}  // namespace zephyr::fixed::reference
