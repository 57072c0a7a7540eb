// Scalar types that component equations are written for.
//
// A component writes its equations once, as a template over the scalar T.
// The framework instantiates them for three scalars:
//   double   - residual evaluation (the hot path);
//   Dual     - forward-mode automatic differentiation: one pass gives the
//              component's local block of dF/dy + cj dF/dy' (no hand-written
//              derivatives anywhere);
//   Pattern  - structural dependency tracking: which local variables (and
//              which time derivatives) each equation depends on. Used once at
//              assembly for the sparsity pattern, the differential/algebraic
//              split (IDASetId) and the structural index check.
//
// Math functions are declared in namespace pneumo for all three scalars, so
// code inside namespace pneumo (and nested namespaces) calls `sqrt(x)`,
// `exp(x)`, `pow(x, a)` unqualified and gets the right overload.
#pragma once

#include <algorithm>
#include <array>
#include <bitset>
#include <cmath>
#include <type_traits>

namespace pneumo {

// Largest number of local variables of one equation block (a component's
// ports and internal variables). Dual carries that many derivative slots but
// only touches the first `n` of them.
inline constexpr int kMaxLocal = 64;

// ---------------------------------------------------------------------------
// Dual: value + gradient with respect to the component's local variables.
// The active slots come in whole groups of four (`n` is a multiple of 4;
// the padding carries derivatives that are exactly 0, as any inactive
// direction does), so that every loop below runs over whole groups, which
// the compiler vectorises without remainder code, and copies stay inline.
class Dual {
 public:
  double v = 0.0;
  int n = 0;  // number of active derivative slots, a multiple of kGroup
  std::array<double, kMaxLocal> d;

  static constexpr int kGroup = 4;
  static_assert(kMaxLocal % kGroup == 0);
  static constexpr int padded(int active) { return (active + kGroup - 1) / kGroup * kGroup; }

  Dual() = default;
  Dual(double value) : v(value), n(0) {}  // NOLINT: implicit from constants is intended
  // Copies move only the active derivatives (a Dual is 0.5 kB; equations
  // copy them through min/max/select and temporaries).
  Dual(const Dual& o) : v(o.v), n(o.n) { copy_groups(o); }
  Dual& operator=(const Dual& o) {
    v = o.v;
    n = o.n;
    copy_groups(o);
    return *this;
  }

  // A seeded variable: value and derivative `seed` in direction `slot`,
  // directions [0, active) active.
  static Dual variable(double value, int slot, double seed, int active) {
    Dual r(value);
    r.n = padded(active);
    std::fill_n(r.d.begin(), r.n, 0.0);
    if (slot >= 0 && slot < active) r.d[slot] = seed;
    return r;
  }
  double deriv(int i) const { return i < n ? d[i] : 0.0; }

  Dual& operator+=(const Dual& b) { return *this = *this + b; }
  Dual& operator-=(const Dual& b) { return *this = *this - b; }
  Dual& operator*=(const Dual& b) { return *this = *this * b; }
  Dual& operator/=(const Dual& b) { return *this = *this / b; }

  // r.d = ca * a.d + cb * b.d over the union of active slots.
  static Dual combine(double value, const Dual& a, double ca, const Dual& b, double cb) {
    Dual r(value);
    const int common = std::min(a.n, b.n);
    r.n = std::max(a.n, b.n);
    for (int i = 0; i < common; i += kGroup)
      for (int k = 0; k < kGroup; ++k) r.d[i + k] = ca * a.d[i + k] + cb * b.d[i + k];
    for (int i = common; i < a.n; i += kGroup)
      for (int k = 0; k < kGroup; ++k) r.d[i + k] = ca * a.d[i + k];
    for (int i = common; i < b.n; i += kGroup)
      for (int k = 0; k < kGroup; ++k) r.d[i + k] = cb * b.d[i + k];
    return r;
  }
  // Chain rule for a unary function with derivative `slope`.
  static Dual chain(double value, const Dual& a, double slope) {
    Dual r(value);
    r.n = a.n;
    for (int i = 0; i < a.n; i += kGroup)
      for (int k = 0; k < kGroup; ++k) r.d[i + k] = slope * a.d[i + k];
    return r;
  }

 private:
  void copy_groups(const Dual& o) {
    for (int i = 0; i < o.n; i += kGroup)
      for (int k = 0; k < kGroup; ++k) d[i + k] = o.d[i + k];
  }

 public:
  friend Dual operator+(const Dual& a, const Dual& b) { return combine(a.v + b.v, a, 1.0, b, 1.0); }
  friend Dual operator-(const Dual& a, const Dual& b) { return combine(a.v - b.v, a, 1.0, b, -1.0); }
  friend Dual operator*(const Dual& a, const Dual& b) { return combine(a.v * b.v, a, b.v, b, a.v); }
  friend Dual operator/(const Dual& a, const Dual& b) {
    const double q = a.v / b.v;
    return combine(q, a, 1.0 / b.v, b, -q / b.v);
  }
  friend Dual operator-(const Dual& a) { return chain(-a.v, a, -1.0); }
  friend Dual operator+(const Dual& a) { return a; }
};

// ---------------------------------------------------------------------------
// Pattern: which local variables a value depends on. Bits [0, kMaxLocal)
// mark y_i, bits [kMaxLocal, 2 kMaxLocal) mark y'_i. The value is carried so
// that branches in component code take the same path as with double.
// `nonlin` marks the dependencies that enter other than linearly with a
// constant coefficient (through a product of two variables, a quotient by a
// variable, a function, a branch): an equation linear in y_i can be solved
// for y_i by one division (System's explicit elimination).
class Pattern {
 public:
  using Bits = std::bitset<2 * kMaxLocal>;
  double v = 0.0;
  Bits deps;
  Bits nonlin;

  Pattern() = default;
  Pattern(double value) : v(value) {}  // NOLINT: implicit from constants is intended

  Pattern& operator+=(const Pattern& b) { return *this = *this + b; }
  Pattern& operator-=(const Pattern& b) { return *this = *this - b; }
  Pattern& operator*=(const Pattern& b) { return *this = *this * b; }
  Pattern& operator/=(const Pattern& b) { return *this = *this / b; }

  // Linear combination: each side keeps its own nonlinear dependencies.
  static Pattern join(double value, const Pattern& a, const Pattern& b) {
    Pattern r(value);
    r.deps = a.deps | b.deps;
    r.nonlin = a.nonlin | b.nonlin;
    return r;
  }
  // Any other function of the operands: all their dependencies nonlinear.
  static Pattern join_nonlinear(double value, const Pattern& a, const Pattern& b) {
    Pattern r(value);
    r.deps = r.nonlin = a.deps | b.deps;
    return r;
  }
  static Pattern keep(double value, const Pattern& a) {
    Pattern r(value);
    r.deps = r.nonlin = a.deps;
    return r;
  }
  friend Pattern operator+(const Pattern& a, const Pattern& b) { return join(a.v + b.v, a, b); }
  friend Pattern operator-(const Pattern& a, const Pattern& b) { return join(a.v - b.v, a, b); }
  friend Pattern operator*(const Pattern& a, const Pattern& b) {
    // A factor without dependencies is a constant coefficient.
    if (a.deps.none() || b.deps.none()) return join(a.v * b.v, a, b);
    return join_nonlinear(a.v * b.v, a, b);
  }
  friend Pattern operator/(const Pattern& a, const Pattern& b) {
    if (b.deps.none()) return join(a.v / b.v, a, b);
    return join_nonlinear(a.v / b.v, a, b);
  }
  friend Pattern operator-(const Pattern& a) {
    Pattern r = a;
    r.v = -a.v;
    return r;
  }
  friend Pattern operator+(const Pattern& a) { return a; }
};

// ---------------------------------------------------------------------------
// value(): the plain number behind any scalar, for branching and output.
inline double value(double x) { return x; }
inline double value(const Dual& x) { return x.v; }
inline double value(const Pattern& x) { return x.v; }

// Comparisons look at the value only.
#define PNEUMO_COMPARE(OP)                                                                     \
  inline bool operator OP(const Dual& a, const Dual& b) { return a.v OP b.v; }                 \
  inline bool operator OP(const Dual& a, double b) { return a.v OP b; }                        \
  inline bool operator OP(double a, const Dual& b) { return a OP b.v; }                        \
  inline bool operator OP(const Pattern& a, const Pattern& b) { return a.v OP b.v; }           \
  inline bool operator OP(const Pattern& a, double b) { return a.v OP b; }                     \
  inline bool operator OP(double a, const Pattern& b) { return a OP b.v; }
PNEUMO_COMPARE(<)
PNEUMO_COMPARE(<=)
PNEUMO_COMPARE(>)
PNEUMO_COMPARE(>=)
#undef PNEUMO_COMPARE

// Mixed arithmetic with double is covered by the implicit constructors.

// ---------------------------------------------------------------------------
// Elementary functions. For each: f(double), f(Dual) with f', f(Pattern).
#define PNEUMO_UNARY(NAME, EXPR_VALUE, EXPR_SLOPE)                          \
  inline double NAME(double x) { return EXPR_VALUE; }                       \
  inline Dual NAME(const Dual& a) {                                         \
    const double x = a.v;                                                   \
    const double f = EXPR_VALUE;                                            \
    (void)f;                                                                \
    return Dual::chain(f, a, EXPR_SLOPE);                                   \
  }                                                                         \
  inline Pattern NAME(const Pattern& a) {                                   \
    const double x = a.v;                                                   \
    return Pattern::keep(EXPR_VALUE, a);                                    \
  }

PNEUMO_UNARY(sqrt, std::sqrt(x), 0.5 / f)
PNEUMO_UNARY(exp, std::exp(x), f)
PNEUMO_UNARY(log, std::log(x), 1.0 / x)
PNEUMO_UNARY(tanh, std::tanh(x), 1.0 - f * f)
PNEUMO_UNARY(sin, std::sin(x), std::cos(x))
PNEUMO_UNARY(cos, std::cos(x), -std::sin(x))
PNEUMO_UNARY(atan, std::atan(x), 1.0 / (1.0 + x * x))
#undef PNEUMO_UNARY

// |x| has a kink at 0; prefer smooth_abs() from smooth.hpp in equations.
inline double abs(double x) { return std::abs(x); }
inline Dual abs(const Dual& a) { return Dual::chain(std::abs(a.v), a, a.v >= 0 ? 1.0 : -1.0); }
inline Pattern abs(const Pattern& a) { return Pattern::keep(std::abs(a.v), a); }

// x^a for a constant exponent.
inline double pow(double x, double a) { return std::pow(x, a); }
inline Dual pow(const Dual& b, double a) {
  const double f = std::pow(b.v, a);
  // a b^(a-1) = a f / b without a second pow where b != 0.
  return Dual::chain(f, b, a == 0.0 ? 0.0 : b.v != 0.0 ? a * f / b.v : a * std::pow(b.v, a - 1.0));
}
inline Pattern pow(const Pattern& b, double a) { return Pattern::keep(std::pow(b.v, a), b); }

// Branch-free selection that keeps the dependencies of both branches in the
// structural pattern (a plain `if` would record only the branch taken at the
// point where the pattern is evaluated).
inline double select(bool c, double a, double b) { return c ? a : b; }
inline Dual select(bool c, const Dual& a, const Dual& b) { return c ? a : b; }
inline Pattern select(bool c, const Pattern& a, const Pattern& b) {
  return Pattern::join_nonlinear(c ? a.v : b.v, a, b);
}

// select() of two branches given as callables: double and Dual evaluate only
// the branch taken (a Dual branch is a whole gradient's work), Pattern both
// (the structure must hold the dependencies of either).
template <class T, class A, class B>
inline T select_lazy(bool c, A&& a, B&& b) {
  if constexpr (std::is_same_v<T, Pattern>)
    return select(c, T(a()), T(b()));
  else
    return c ? T(a()) : T(b());
}

template <class T>
inline T min(const T& a, const T& b) { return select(value(a) <= value(b), a, b); }
template <class T>
inline T max(const T& a, const T& b) { return select(value(a) >= value(b), a, b); }
inline double min(double a, double b) { return std::min(a, b); }
inline double max(double a, double b) { return std::max(a, b); }

inline bool isfinite(double x) { return std::isfinite(x); }

}  // namespace pneumo
