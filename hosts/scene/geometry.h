// hosts/scene/geometry.h — 3-vectors and 3×4 affine transforms, shared by the scene, the tracers
// and the exporters.
//
// Vec3T is templated on the scalar so the tracer can run in float or double (docs/background.md,
// "Precision, accuracy, speed": the accuracy chart needs both); scenes are always held in double
// (Vec3).
#pragma once

#include <cmath>

namespace zephyr {

template <typename T>
struct Vec3T {
  T x = 0, y = 0, z = 0;

  constexpr Vec3T() = default;
  constexpr Vec3T(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
  template <typename U>
  constexpr explicit Vec3T(const Vec3T<U>& v) : x(T(v.x)), y(T(v.y)), z(T(v.z)) {}

  constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3T operator+(const Vec3T& b) const { return {x + b.x, y + b.y, z + b.z}; }
  constexpr Vec3T operator-(const Vec3T& b) const { return {x - b.x, y - b.y, z - b.z}; }
  constexpr Vec3T operator-() const { return {-x, -y, -z}; }
  constexpr Vec3T operator*(T s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3T operator/(T s) const { return {x / s, y / s, z / s}; }
  constexpr Vec3T& operator+=(const Vec3T& b) {
    x += b.x;
    y += b.y;
    z += b.z;
    return *this;
  }
  constexpr bool operator==(const Vec3T&) const = default;
};

template <typename T>
constexpr Vec3T<T> operator*(T s, const Vec3T<T>& v) {
  return v * s;
}
template <typename T>
constexpr T Dot(const Vec3T<T>& a, const Vec3T<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <typename T>
constexpr Vec3T<T> Cross(const Vec3T<T>& a, const Vec3T<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename T>
T Length(const Vec3T<T>& v) {
  return std::sqrt(Dot(v, v));
}
template <typename T>
Vec3T<T> Normalize(const Vec3T<T>& v) {
  return v / Length(v);
}
// The largest |component| (the infinity norm): a bound that never overflows.
template <typename T>
T MaxAbs(const Vec3T<T>& v) {
  return std::fmax(std::fabs(v.x), std::fmax(std::fabs(v.y), std::fabs(v.z)));
}
// v divided by its largest |component|, so Length and Normalize of the result neither
// overflow nor underflow (v = 0 stays 0).
template <typename T>
Vec3T<T> ScaledDown(const Vec3T<T>& v) {
  const T m = MaxAbs(v);
  return m > T(0) ? v / m : v;
}
// Component-wise product (colours).
template <typename T>
constexpr Vec3T<T> Mul(const Vec3T<T>& a, const Vec3T<T>& b) {
  return {a.x * b.x, a.y * b.y, a.z * b.z};
}

using Vec3 = Vec3T<double>;

// An affine map p -> A p + b, stored as the top three rows of a 4×4 matrix (the bottom row
// of an affine matrix is always 0 0 0 1). m[r][3] is the translation.
struct Affine {
  double m[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};

  Vec3 ApplyPoint(const Vec3& p) const;
  Vec3 ApplyVector(const Vec3& v) const;  // linear part only
  // Applies the transpose of the linear part (normals use the inverse-transpose: a normal
  // n in object space maps to (A⁻¹)ᵀ n, i.e. inverse.ApplyTransposed(n)).
  Vec3 ApplyTransposed(const Vec3& v) const;
  double Determinant() const;  // of the linear part (may overflow or underflow)
  // ‖A‖∞ of the linear part: the largest row sum of |entries| (|A v|∞ <= this · |v|∞).
  double LinearNormInf() const;
  // A power of two 2^k with max |A_ij| <= 2^k < 2 max |A_ij| over the linear part A (1 when
  // A is zero): A / LinearScale() has entries in [-1, 1], exactly (only the exponent moves).
  double LinearScale() const;
  // det(A / LinearScale()): the determinant free of the matrix's scale, |value| <= 6, so a
  // uniform scale of 1e-152 or 1e120 is as regular as the identity. Near 0 (below
  // 1e-12) the map is singular to double precision.
  double RelativeDeterminant() const;
  // The inverse map, computed on A / LinearScale() so that no intermediate overflows or
  // underflows. Callers must check that RelativeDeterminant() is not (nearly) zero.
  Affine Inverse() const;
  Affine operator*(const Affine& b) const;  // (this ∘ b)(p) = this(b(p))
  bool IsIdentity() const;
};

}  // namespace zephyr
