// The one place the kernels touch elementary functions and literals.
// double and float forward to <cmath>; a fixed-point type adds its own overloads
// of these functions to osc::math (the kernels call them qualified) and a
// constructor from double for literals (lit<S>).
#pragma once

#include <cmath>

namespace osc {

/// Literal of the kernel's scalar type (evaluated at compile time for float/double).
template <class S>
constexpr S lit(double v) { return static_cast<S>(v); }

namespace math {
inline float sin(float v) { return std::sin(v); }
inline float cos(float v) { return std::cos(v); }
inline float sqrt(float v) { return std::sqrt(v); }
inline float exp(float v) { return std::exp(v); }
inline float abs(float v) { return std::fabs(v); }
inline float atan2(float y, float x) { return std::atan2(y, x); }
inline float asin(float v) { return std::asin(v); }
inline bool isfinite(float v) { return std::isfinite(v); }
inline double sin(double v) { return std::sin(v); }
inline double cos(double v) { return std::cos(v); }
inline double sqrt(double v) { return std::sqrt(v); }
inline double exp(double v) { return std::exp(v); }
inline double abs(double v) { return std::fabs(v); }
inline double atan2(double y, double x) { return std::atan2(y, x); }
inline double asin(double v) { return std::asin(v); }
inline bool isfinite(double v) { return std::isfinite(v); }

/// sgn with sgn(0) = 0, eq. (3).
template <class S>
S sgn(S v) { return v > S(0) ? S(1) : (v < S(0) ? S(-1) : S(0)); }

/// True when every coefficient of an Eigen expression is finite.
template <class Derived>
bool all_finite(const Derived& m) {
  for (int j = 0; j < m.cols(); ++j)
    for (int i = 0; i < m.rows(); ++i)
      if (!isfinite(m(i, j))) return false;
  return true;
}
}  // namespace math
}  // namespace osc
