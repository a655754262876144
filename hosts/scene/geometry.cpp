#include "hosts/scene/geometry.h"

#include <algorithm>
#include <cmath>

namespace zephyr {

Vec3 Affine::ApplyPoint(const Vec3& p) const {
  return {m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3],
          m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3],
          m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3]};
}

Vec3 Affine::ApplyVector(const Vec3& v) const {
  return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
          m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
          m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

Vec3 Affine::ApplyTransposed(const Vec3& v) const {
  return {m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z,
          m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
          m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z};
}

double Affine::LinearNormInf() const {
  double norm = 0;
  for (int i = 0; i < 3; ++i)
    norm = std::max(norm, std::abs(m[i][0]) + std::abs(m[i][1]) + std::abs(m[i][2]));
  return norm;
}

double Affine::Determinant() const {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

double Affine::LinearScale() const {
  double largest = 0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) largest = std::max(largest, std::abs(m[r][c]));
  if (!(largest > 0) || !std::isfinite(largest)) return 1;
  int exponent = 0;
  std::frexp(largest, &exponent);  // largest = f · 2^exponent, 0.5 <= f < 1
  return std::ldexp(1.0, exponent);
}

namespace {
// The map with its linear part divided by s (a power of two: exact but for subnormal
// results); the translation kept.
Affine LinearDividedBy(Affine a, double s) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a.m[r][c] /= s;
  return a;
}
}  // namespace

double Affine::RelativeDeterminant() const {
  return LinearDividedBy(*this, LinearScale()).Determinant();
}

Affine Affine::Inverse() const {
  // (A / s)⁻¹ = s A⁻¹: invert the scaled part (entries in [-1, 1]; no overflow or underflow
  // in the adjugate or the determinant), then divide by s.
  const double s = LinearScale();
  const Affine a = LinearDividedBy(*this, s);
  const double inv = 1.0 / (a.Determinant() * s);
  Affine r;
  // Adjugate of the 3×3 linear part, divided by the determinant.
  r.m[0][0] = (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) * inv;
  r.m[0][1] = (a.m[0][2] * a.m[2][1] - a.m[0][1] * a.m[2][2]) * inv;
  r.m[0][2] = (a.m[0][1] * a.m[1][2] - a.m[0][2] * a.m[1][1]) * inv;
  r.m[1][0] = (a.m[1][2] * a.m[2][0] - a.m[1][0] * a.m[2][2]) * inv;
  r.m[1][1] = (a.m[0][0] * a.m[2][2] - a.m[0][2] * a.m[2][0]) * inv;
  r.m[1][2] = (a.m[0][2] * a.m[1][0] - a.m[0][0] * a.m[1][2]) * inv;
  r.m[2][0] = (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]) * inv;
  r.m[2][1] = (a.m[0][1] * a.m[2][0] - a.m[0][0] * a.m[2][1]) * inv;
  r.m[2][2] = (a.m[0][0] * a.m[1][1] - a.m[0][1] * a.m[1][0]) * inv;
  // Translation: -A⁻¹ b.
  const Vec3 b{m[0][3], m[1][3], m[2][3]};
  const Vec3 t = r.ApplyVector(b);
  r.m[0][3] = -t.x;
  r.m[1][3] = -t.y;
  r.m[2][3] = -t.z;
  return r;
}

Affine Affine::operator*(const Affine& b) const {
  Affine r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) {
      double s = (j == 3) ? m[i][3] : 0.0;
      for (int k = 0; k < 3; ++k) s += m[i][k] * b.m[k][j];
      r.m[i][j] = s;
    }
  }
  return r;
}

bool Affine::IsIdentity() const {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j)
      if (m[i][j] != (i == j ? 1.0 : 0.0)) return false;
  return true;
}

}  // namespace zephyr
