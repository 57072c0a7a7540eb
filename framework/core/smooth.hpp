// Smooth replacements for the kinks of physics formulas (|x|, max(x, 0),
// sign(x), sqrt(dp)). Newton iterations and the AD Jacobian need residuals
// that are continuously differentiable; each helper takes an explicit scale
// below which it departs from the sharp formula, so that the regularisation
// is a visible modelling parameter, not a hidden constant.
#pragma once

#include "framework/core/scalar.hpp"

namespace pneumo {

// sqrt(x^2 + eps^2): |x| for |x| >> eps, eps at 0, smooth everywhere.
template <class T>
inline T smooth_abs(const T& x, double eps) {
  return sqrt(x * x + eps * eps);
}

// Smooth max(x, 0) = (x + smooth_abs(x)) / 2. Note smooth_pos(x) -
// smooth_pos(-x) == x (to rounding), which keeps upwinded energy flows
// conservative. For x << -eps the sum x + |x| cancels catastrophically (the
// stream-mixing weights of receiving ports came out as rounding noise, and
// so did their derivatives); there the same value is computed as
// eps^2 / (2 (smooth_abs(x) - x)), which is exact algebra and stable.
template <class T>
inline T smooth_pos_given_abs(const T& x, const T& s, double eps) {  // s = smooth_abs(x, eps)
  return select_lazy<T>(value(x) >= 0.0, [&] { return 0.5 * (x + s); }, [&] { return 0.5 * eps * eps / (s - x); });
}
template <class T>
inline T smooth_pos(const T& x, double eps) {
  return smooth_pos_given_abs(x, smooth_abs(x, eps), eps);
}

// smooth_pos(x) and smooth_pos(-x) together, with one smooth_abs (the same
// values, bit for bit: sqrt((-x)^2 + eps^2) is sqrt(x^2 + eps^2)).
template <class T>
inline void smooth_pos_pair(const T& x, double eps, T& pos, T& neg) {
  const T s = smooth_abs(x, eps);
  pos = smooth_pos_given_abs(x, s, eps);
  neg = smooth_pos_given_abs(T(-x), s, eps);
}

// sign(x) regularised with tanh over the scale eps.
template <class T>
inline T smooth_sign(const T& x, double eps) {
  return tanh(x / eps);
}

// Regularised signed square root: sign(x) sqrt(|x|) for |x| >> delta, linear
// through 0 with finite slope (Modelica's regRoot idea, own formulation):
// x / (x^2 + delta^2)^(1/4).
template <class T>
inline T reg_root(const T& x, double delta) {
  return x / sqrt(sqrt(x * x + delta * delta));
}

// Linear interpolation in a table of (x, y) rows sorted by x, clamped at the
// ends. The row is chosen by value; within a row the result is linear in x,
// so AD derivatives are the segment slopes.
template <class T, class Table>
inline T interpolate(const Table& table, const T& x) {
  const auto n = table.size();
  if (n == 1) return T(table[0][1]);
  const double xv = value(x);
  std::size_t i = 0;
  while (i + 2 < n && xv > table[i + 1][0]) ++i;
  const double x0 = table[i][0], x1 = table[i + 1][0];
  const double y0 = table[i][1], y1 = table[i + 1][1];
  if (xv <= x0 && i == 0) return T(y0) + 0.0 * x;
  if (xv >= x1 && i + 2 == n) return T(y1) + 0.0 * x;
  return y0 + (y1 - y0) / (x1 - x0) * (x - x0);
}

}  // namespace pneumo
