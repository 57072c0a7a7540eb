// Physical units for netlists: parsing "5 bar", "0.4 dm3/(s*bar)", "20 degC"
// into SI values plus a dimension, so that components only ever see SI.
//
// Design notes (the why):
//  * Only four base dimensions are tracked (m, kg, s, K): that is all a
//    pneumatic drive model needs, and keeping the set small keeps the error
//    messages readable ("kg m^-1 s^-2" rather than a 7-tuple).
//  * Angles and revolution counts are dimensionless. "rad" and "rev" both have
//    scale 1 (a revolution *count*, not 2*pi rad); "deg" converts to radians.
//    Components decide whether a dimensionless number means rad or rev.
//  * Affine units (degC, degF) and gauge pressures (barg, psig, ...) only make
//    sense for absolute values, never inside a compound unit ("degC/s" would be
//    ambiguous between a rate and an offset), so they are accepted only as the
//    whole unit.
//  * Gauge pressures depend on the ambient pressure, which is not known when a
//    unit is parsed: parse_unit() marks them with Unit::gauge and offset 0, and
//    the ambient pressure is added by parse_quantity()/to_si().
//  * Columns in ParseError are 0-based byte offsets into the parsed text
//    (non-ASCII symbols such as "µ" or "°" occupy more than one byte).
#pragma once

// glibc's <signal.h> defines `si_value` as a macro (siginfo_t member access),
// which would silently rewrite Quantity::si_value in any file that also
// includes <signal.h> (GoogleTest does, via <sys/wait.h>). Include it here
// first and drop the macro, so the include order never matters; its header
// guard keeps later includes from redefining it. Code that needs
// siginfo_t::si_value must spell it `_sifields._rt.si_sigval` instead.
#include <csignal>
#ifdef si_value
#undef si_value
#endif

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace pneumo::units {

// Exponents of SI base dimensions used by pneumo: length, mass, time, temperature.
struct Dimension {
  int m = 0, kg = 0, s = 0, K = 0;
  bool operator==(const Dimension&) const = default;
  bool dimensionless() const;
  std::string to_string() const;  // e.g. "kg m^-1 s^-2"; "1" if dimensionless
};

// Exponent arithmetic. Throws std::overflow_error if an exponent leaves the
// range of int (cannot happen for anything parse_unit produces).
Dimension operator*(Dimension, Dimension);
Dimension operator/(Dimension, Dimension);
Dimension pow(Dimension, int);

// Frequently used dimensions, for parameter specs and checks.
namespace dims {
inline constexpr Dimension none{};
inline constexpr Dimension length{.m = 1};
inline constexpr Dimension mass{.kg = 1};
inline constexpr Dimension time{.s = 1};
inline constexpr Dimension temperature{.K = 1};
inline constexpr Dimension area{.m = 2};
inline constexpr Dimension volume{.m = 3};
inline constexpr Dimension velocity{.m = 1, .s = -1};
inline constexpr Dimension acceleration{.m = 1, .s = -2};
inline constexpr Dimension frequency{.s = -1};
inline constexpr Dimension force{.m = 1, .kg = 1, .s = -2};
inline constexpr Dimension pressure{.m = -1, .kg = 1, .s = -2};
inline constexpr Dimension energy{.m = 2, .kg = 1, .s = -2};
inline constexpr Dimension power{.m = 2, .kg = 1, .s = -3};
inline constexpr Dimension density{.m = -3, .kg = 1};
inline constexpr Dimension mass_flow{.kg = 1, .s = -1};
inline constexpr Dimension volume_flow{.m = 3, .s = -1};
// ISO 6358 sonic conductance C: volume flow per pressure, m^4 s kg^-1.
inline constexpr Dimension sonic_conductance{.m = 4, .kg = -1, .s = 1};
}  // namespace dims

// A unit: si_value = scale * value + offset. offset != 0 only for affine units
// (degC, degF). Gauge pressures have gauge == true and offset 0 here, because
// their offset is the ambient pressure, which is supplied when converting.
struct Unit {
  double scale = 1;
  double offset = 0;
  Dimension dim;
  bool affine() const { return offset != 0 || gauge; }
  bool gauge = false;
};

// How result files show a value in a unit other than SI:
// shown = (si - offset) / scale, headed by `unit` (bar, barg, mm, degC; for
// a gauge unit the offset holds the ambient pressure). Empty unit: SI as is.
struct DisplayUnit {
  std::string unit;
  double scale = 1.0, offset = 0.0;
  double shown(double si) const { return (si - offset) / scale; }
};

// Thrown for every malformed unit or quantity. what() is a human readable
// message naming the offending token (e.g. "unknown unit 'furlong'; ..."); it
// does not repeat the whole text or the column, which callers add themselves.
struct ParseError : std::runtime_error {
  std::size_t column;  // 0-based column (byte offset) in the parsed text
  ParseError(const std::string& what, std::size_t column);
};

// Parse a unit expression: "Pa", "bar", "dm3/(s*bar)", "m/s^2", "N*s/m",
// "W/(m2*K)", "kg/m^3", "1/s", "1" or "" (dimensionless).
// Grammar (informal):
//   expr   := term { ('*' | '.' | '·' | whitespace | '/') term }
//   term   := factor [ '^' int | '**' int | attached int ("m3", "s-1") ]
//   factor := name | '1' | '(' expr ')'
// Multiplication after a '/' at the same parenthesis level ("W/m2*K") is
// rejected as ambiguous; chained division ("kg/m/s") is allowed.
Unit parse_unit(std::string_view text);

// Parse "5 bar", "4 barg", "32 mm", "0.4 dm3/(s*bar)", "20 degC", "1e-6",
// "-3.5e+2 N", " 2  bar ". Plain numbers have unit "1" (had_unit == false;
// the caller decides whether that means SI). Gauge pressure units add
// ambient_pressure_pa to the SI value.
struct Quantity {
  double si_value;
  Dimension dim;
  bool had_unit;
  bool gauge;
};
Quantity parse_quantity(std::string_view text, double ambient_pressure_pa = 101325.0);

// Dimension of a unit expression used in parameter specs ("Pa", "m3", "kg/s",
// "1", "rev"). Accepts affine/gauge units too (temperature/pressure dimension).
Dimension dimension_of(std::string_view unit_text);

// Convert a value given in `unit` to SI (adds ambient pressure for gauge units).
double to_si(const Unit& unit, double value, double ambient_pressure_pa = 101325.0);

// Name of the coherent SI unit for a dimension: "Pa", "N", "J", "W" for the
// derived units pneumo uses most, otherwise Dimension::to_string().
std::string si_unit_name(Dimension dim);

// Format an SI value of a given dimension back into a readable string with its
// SI unit, e.g. (5e5, pressure) -> "500000 Pa", (0.032, length) -> "0.032 m".
// Uses the shortest representation that parses back to the same double.
std::string format_si(double si_value, Dimension dim);

// The one way a value of dimension `dim` meets a unit it is shown in: `unit_text`
// ("ms", "barg", "mm", "degC") or, when empty, the SI unit (si_unit_name).
// Throws ParseError for an unknown unit and DimensionMismatch when the unit is
// not of `dim` (what() names both, e.g. "'bar' is a pressure (kg m^-1 s^-2),
// not s").
struct DimensionMismatch : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};
DisplayUnit display_unit(std::string_view unit_text, Dimension dim, double ambient_pressure_pa = 101325.0);

// The quantities a netlist's `display:` names ("pressure", "length",
// "temperature", "time", ...) and their dimensions, in a fixed order.
struct NamedQuantity {
  const char* name;
  Dimension dim;
};
const std::vector<NamedQuantity>& named_quantities();

// The unit `unit_text` read as a difference, for values that are not an
// absolute pressure (a pressure difference, a sum of pressures): a gauge
// unit's plain twin ("barg" -> "bar", "psig" -> "psi"), any other unit as is.
std::string difference_unit(std::string_view unit_text);

// A number written without a unit is SI. For the dimensions people habitually
// write in other units, a bare number far outside what its SI value
// plausibly is - `bore: 40` (40 m), `p: 6` (6 Pa), `T: 20` (20 K),
// `C: 0.4` (0.4 m3/(s*Pa)) - was almost surely meant in the habitual unit.
// Returns that unit ("mm", "bar", "degC", "L", "mm2", "dm3/(s*bar)") when
// `si_value` is implausible as SI for `dim`; "" when it is plausible or the
// dimension has no habit (mass, time, force: SI is what people write).
std::string habitual_unit_if_implausible(double si_value, Dimension dim);

// Every unit name parse_unit() accepts as a single token (for docs/completion).
std::vector<std::string> known_unit_names();

}  // namespace pneumo::units
