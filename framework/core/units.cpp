#include "framework/core/units.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <system_error>
#include <unordered_map>
#include <utility>

namespace pneumo::units {

// ---------------------------------------------------------------------------
// Dimension
// ---------------------------------------------------------------------------

namespace {

// Exponent arithmetic is done in long long and range-checked, so that no input
// can ever cause signed overflow (UB).
int checked_exponent(long long v) {
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max())
    throw std::overflow_error("pneumo::units: dimension exponent overflow");
  return static_cast<int>(v);
}

}  // namespace

bool Dimension::dimensionless() const { return m == 0 && kg == 0 && s == 0 && K == 0; }

std::string Dimension::to_string() const {
  if (dimensionless()) return "1";
  // Mass first, as in the conventional "kg m^-1 s^-2" for pressure.
  const std::pair<const char*, int> parts[] = {{"kg", kg}, {"m", m}, {"s", s}, {"K", K}};
  std::string out;
  for (const auto& [name, e] : parts) {
    if (e == 0) continue;
    if (!out.empty()) out += ' ';
    out += name;
    if (e != 1) out += '^' + std::to_string(e);
  }
  return out;
}

Dimension operator*(Dimension a, Dimension b) {
  return {checked_exponent(static_cast<long long>(a.m) + b.m),
          checked_exponent(static_cast<long long>(a.kg) + b.kg),
          checked_exponent(static_cast<long long>(a.s) + b.s),
          checked_exponent(static_cast<long long>(a.K) + b.K)};
}

Dimension operator/(Dimension a, Dimension b) {
  return {checked_exponent(static_cast<long long>(a.m) - b.m),
          checked_exponent(static_cast<long long>(a.kg) - b.kg),
          checked_exponent(static_cast<long long>(a.s) - b.s),
          checked_exponent(static_cast<long long>(a.K) - b.K)};
}

Dimension pow(Dimension d, int e) {
  return {checked_exponent(static_cast<long long>(d.m) * e),
          checked_exponent(static_cast<long long>(d.kg) * e),
          checked_exponent(static_cast<long long>(d.s) * e),
          checked_exponent(static_cast<long long>(d.K) * e)};
}

ParseError::ParseError(const std::string& what, std::size_t column)
    : std::runtime_error(what), column(column) {}

// ---------------------------------------------------------------------------
// Unit table
// ---------------------------------------------------------------------------

namespace {

using Table = std::map<std::string, Unit, std::less<>>;

// Exact definitions rather than rounded constants, so conversions are as
// precise as double allows (e.g. psi = lbf/in^2 = 6894.757293168... Pa).
constexpr double kPound = 0.45359237;            // kg, international pound
constexpr double kStandardGravity = 9.80665;     // m/s^2
constexpr double kInch = 0.0254;                 // m
constexpr double kPsi = kPound * kStandardGravity / (kInch * kInch);
constexpr double kCelsiusOffset = 273.15;        // K at 0 degC
constexpr double kFahrenheitScale = 5.0 / 9.0;
constexpr double kFahrenheitOffset = 459.67 * 5.0 / 9.0;  // K at 0 degF

struct Prefix {
  char key;  // letter used in the per-unit "allowed prefixes" strings
  const char* symbol;
  double factor;
};

// 'u' stands for micro and also enables the micro sign "µ" (U+00B5) and the
// Greek letter mu "μ" (U+03BC), which are both found in the wild.
constexpr Prefix kPrefixes[] = {
    {'G', "G", 1e9},  {'M', "M", 1e6},        {'k', "k", 1e3},        {'h', "h", 1e2},
    {'d', "d", 1e-1}, {'c', "c", 1e-2},       {'m', "m", 1e-3},       {'u', "u", 1e-6},
    {'u', "\xC2\xB5", 1e-6},                  {'u', "\xCE\xBC", 1e-6}, {'n', "n", 1e-9},
};

struct BaseUnit {
  const char* name;
  double scale;
  Dimension dim;
  // Prefixes that "make sense" for this unit; deliberately restrictive so that
  // typos like "cbar" or "kK" are reported instead of silently accepted.
  const char* prefixes;
};

const BaseUnit kBaseUnits[] = {
    // Length, mass, time.
    {"m", 1, dims::length, "kdcmun"},
    {"g", 1e-3, dims::mass, "kmu"},
    {"s", 1, dims::time, "mun"},
    {"min", 60, dims::time, ""},
    {"h", 3600, dims::time, ""},
    {"Hz", 1, dims::frequency, "kM"},
    // Mechanics.
    {"N", 1, dims::force, "kMm"},
    {"J", 1, dims::energy, "kMm"},
    {"W", 1, dims::power, "kMm"},
    // Pressure (absolute unless suffixed, see below).
    {"Pa", 1, dims::pressure, "hkMG"},
    {"bar", 1e5, dims::pressure, "m"},
    {"psi", kPsi, dims::pressure, ""},
    {"atm", 101325, dims::pressure, ""},
    // Temperature (absolute).
    {"K", 1, dims::temperature, ""},
    // Volume: both spellings of the litre are common.
    {"L", 1e-3, dims::volume, "mcdu"},
    {"l", 1e-3, dims::volume, "mcdu"},
    // Dimensionless.
    {"rev", 1, dims::none, ""},
    {"rad", 1, dims::none, "m"},
    {"deg", std::numbers::pi / 180, dims::none, ""},
    {"\xC2\xB0", std::numbers::pi / 180, dims::none, ""},  // "°" alone: angle
    {"%", 0.01, dims::none, ""},
};

// Pressure units that get explicit absolute/gauge spellings.
constexpr const char* kPressureUnits[] = {"Pa", "hPa", "kPa", "MPa", "bar", "mbar", "psi"};
// "bara"/"barg"-style single-letter suffixes are idiomatic only for these;
// for the pascal family only the gauge "g" is in use ("kPag"), "kPaa" is not.
constexpr const char* kLetterSuffixUnits[] = {"bar", "mbar", "psi"};

const Table& unit_table() {
  static const Table table = [] {
    Table t;
    for (const BaseUnit& b : kBaseUnits) {
      t.emplace(b.name, Unit{b.scale, 0, b.dim});
      for (const Prefix& p : kPrefixes) {
        if (std::string_view(b.prefixes).find(p.key) == std::string_view::npos) continue;
        t.emplace(std::string(p.symbol) + b.name, Unit{p.factor * b.scale, 0, b.dim});
      }
    }
    for (const char* name : kPressureUnits) {
      const Unit abs = t.at(name);
      Unit gauge = abs;
      gauge.gauge = true;
      for (const char* suffix : {"_abs", "_a", "(a)"}) t.emplace(std::string(name) + suffix, abs);
      for (const char* suffix : {"g", "_rel", "_g", "(g)"}) t.emplace(std::string(name) + suffix, gauge);
    }
    for (const char* name : kLetterSuffixUnits) t.emplace(std::string(name) + "a", t.at(name));
    const Unit celsius{1, kCelsiusOffset, dims::temperature};
    const Unit fahrenheit{kFahrenheitScale, kFahrenheitOffset, dims::temperature};
    t.emplace("degC", celsius);
    t.emplace("\xC2\xB0" "C", celsius);
    t.emplace("degF", fahrenheit);
    t.emplace("\xC2\xB0" "F", fahrenheit);
    return t;
  }();
  return table;
}

// Units people type that are deliberately not supported, with the reason.
// Returning a hint instead of a bare "unknown unit" saves a trip to the docs.
std::string hint_for(std::string_view name, int exponent) {
  if (name == "Nl" || name == "NL" || name == "nl" || (name == "Nm" && exponent == 3))
    return "normal litres/cubic metres measure an amount of gas at reference conditions, not a "
           "volume; convert to a mass (kg, kg/s) with the reference density instead";
  if (name == "Nm") return "for newton metres write 'N*m' or 'N m'";
  if (name == "sl" || name == "slm" || name == "slpm" || name == "SLPM" || name == "sccm" ||
      name == "scfm")
    return "standard-condition flow units measure an amount of gas, not a volume; convert to kg/s "
           "with the reference density instead";
  if (name == "C" || name == "F" || name == "degK" || name == "\xC2\xB0K")
    return "write temperatures as K, degC or degF";
  if (name == "rpm") return "write rotational speed as 'rev/min'";
  if (name == "sec") return "seconds are 's'";
  if (name == "hr") return "hours are 'h'";
  return {};
}

std::string ascii_lower(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return out;
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

// Close matches by case-insensitive edit distance ("kpa" -> "kPa", "bra" ->
// "bar"). The table has a few hundred short names, so brute force is cheap.
std::vector<std::string> close_matches(std::string_view name) {
  if (name.size() > 32) return {};  // garbage, not a typo
  const std::string lname = ascii_lower(name);
  const std::size_t limit = name.size() <= 3 ? 1 : 2;
  std::vector<std::pair<std::size_t, std::string>> found;
  for (const auto& [candidate, unit] : unit_table()) {
    // Case-only mismatches have distance 0 and therefore come first.
    const std::size_t d = edit_distance(lname, ascii_lower(candidate));
    if (d <= limit) found.emplace_back(d, candidate);
  }
  std::sort(found.begin(), found.end());
  std::vector<std::string> out;
  for (std::size_t i = 0; i < found.size() && i < 4; ++i) out.push_back(found[i].second);
  return out;
}

// ---------------------------------------------------------------------------
// Parser
// ---------------------------------------------------------------------------

// Exponents beyond this are certainly typos; the bound also keeps every
// intermediate exponent product far away from int overflow.
constexpr int kMaxExponent = 64;
// Bounded recursion: deeply nested parentheses must not blow the stack.
constexpr int kMaxDepth = 32;

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_ascii_letter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }

// Length of a multi-byte symbol that may appear inside a unit name ("µ", "μ",
// "°"), or 0.
std::size_t name_symbol_length(std::string_view rest) {
  if (rest.starts_with("\xC2\xB5") || rest.starts_with("\xCE\xBC") || rest.starts_with("\xC2\xB0")) return 2;
  return 0;
}

// Length of a multiplication operator at the start of `rest`, or 0. The
// middle dot "·" (U+00B7) is accepted alongside '*' and '.'.
std::size_t mul_operator_length(std::string_view rest) {
  if (rest.starts_with("**")) return 0;  // that is an exponent
  if (rest.starts_with('*') || rest.starts_with('.')) return 1;
  if (rest.starts_with("\xC2\xB7")) return 2;
  return 0;
}

struct Special {  // an affine temperature or gauge pressure token
  std::string name;
  std::size_t begin = 0, end = 0;
  bool gauge = false;
  bool combined = false;  // raised to a power, or a second special token seen
};

class Parser {
 public:
  // `text` is the whole string being parsed (for messages and columns);
  // parsing starts at `pos` and stops at the end of `text`.
  Parser(std::string_view text, std::size_t pos) : text_(text), pos_(pos) {}

  Unit parse_whole_unit() {
    skip_space();
    const std::size_t begin = pos_;
    if (at_end()) return Unit{};
    Unit u = parse_product(0);
    skip_space();
    if (!at_end()) {
      if (peek() == ')') fail("unbalanced ')': no matching '('", pos_);
      if (peek() == '(') fail("unexpected '(': write an operator ('*' or '/') before it", pos_);
      fail("unexpected " + describe_at(pos_) + " in unit", pos_);
    }
    std::size_t end = text_.size();
    while (end > begin && is_space(text_[end - 1])) --end;
    if (special_) {
      // Affine and gauge units have an offset, which has no meaning once the
      // unit is multiplied, divided or raised to a power.
      if (special_->combined || special_->begin != begin || special_->end != end) {
        if (special_->gauge)
          fail("gauge pressure unit '" + special_->name +
                   "' can only be used on its own; inside a compound unit use an absolute unit "
                   "such as bar or Pa (pressure differences are the same)",
               special_->begin);
        fail("temperature unit '" + special_->name +
                 "' has an offset and can only be used on its own; use K for temperature "
                 "differences and rates (e.g. K/s)",
             special_->begin);
      }
      return special_unit_;
    }
    return u;
  }

  // The message does not repeat the text or column: callers (the netlist
  // reader) already quote the text and turn `column` into a file position.
  [[noreturn]] void fail(const std::string& message, std::size_t column) const {
    throw ParseError(message, column);
  }

  // Human readable name of the character at `at`, keeping UTF-8 sequences whole.
  std::string describe_at(std::size_t at) const {
    if (at >= text_.size()) return "end of input";
    const unsigned char c = static_cast<unsigned char>(text_[at]);
    std::size_t len = 1;
    if (c >= 0xF0) len = 4;
    else if (c >= 0xE0) len = 3;
    else if (c >= 0xC0) len = 2;
    len = std::min(len, text_.size() - at);
    if (c < 0x20 || c == 0x7F) return "control character";
    return "'" + std::string(text_.substr(at, len)) + "'";
  }

 private:
  bool at_end() const { return pos_ >= text_.size(); }
  char peek() const { return at_end() ? '\0' : text_[pos_]; }
  std::string_view rest() const { return text_.substr(pos_); }
  void skip_space() {
    while (!at_end() && is_space(peek())) ++pos_;
  }

  bool starts_factor() const {
    const char c = peek();
    return is_ascii_letter(c) || c == '_' || c == '%' || c == '(' || is_digit(c) ||
           name_symbol_length(rest()) > 0;
  }

  // Combine two units, rejecting dimensions or scales no sane unit has.
  Unit checked(Unit u, std::size_t column) const {
    for (int e : {u.dim.m, u.dim.kg, u.dim.s, u.dim.K})
      if (e > kMaxExponent || e < -kMaxExponent) fail("exponent too large", column);
    if (!std::isfinite(u.scale) || u.scale == 0) fail("unit scale out of range", column);
    return u;
  }

  Unit parse_product(int depth) {
    Unit acc = parse_power(depth);
    bool after_division = false;
    for (;;) {
      const std::size_t before_space = pos_;
      skip_space();
      const bool had_space = pos_ != before_space;
      const std::size_t op_col = pos_;
      bool divide = false;
      if (std::size_t n = mul_operator_length(rest())) {
        pos_ += n;
      } else if (peek() == '/') {
        divide = true;
        ++pos_;
      } else if (had_space && !at_end() && starts_factor()) {
        // Juxtaposition: "N m" means N*m.
      } else {
        pos_ = before_space;  // leave trailing space for the caller
        return acc;
      }
      if (!divide && after_division)
        fail("ambiguous unit: multiplication after '/' - use parentheses, e.g. 'W/(m2*K)'", op_col);
      skip_space();
      if (at_end()) fail("unit ends after an operator", op_col);
      const Unit rhs = parse_power(depth);
      Unit next;
      if (divide) {
        next.scale = acc.scale / rhs.scale;
        next.dim = acc.dim / rhs.dim;
        after_division = true;
      } else {
        next.scale = acc.scale * rhs.scale;
        next.dim = acc.dim * rhs.dim;
      }
      acc = checked(next, op_col);
    }
  }

  Unit parse_power(int depth) {
    const std::size_t begin = pos_;
    bool is_name = false;
    Unit base = parse_factor(depth, is_name);
    const std::size_t factor_end = pos_;

    std::optional<int> exponent;
    std::size_t exp_col = pos_;
    if (is_name && (is_digit(peek()) || ((peek() == '-' || peek() == '+') && pos_ + 1 < text_.size() &&
                                         is_digit(text_[pos_ + 1])))) {
      // Attached exponent: "m3", "s-1".
      exponent = parse_int();
    } else {
      skip_space();
      exp_col = pos_;
      std::size_t n = rest().starts_with("**") ? 2 : rest().starts_with('^') ? 1 : 0;
      if (n == 0) {
        pos_ = factor_end;
      } else {
        pos_ += n;
        skip_space();
        if (peek() == '(') {  // "m^(-3)"
          ++pos_;
          skip_space();
          exponent = parse_int();
          skip_space();
          if (peek() != ')') fail("expected ')' after exponent", pos_);
          ++pos_;
        } else {
          exponent = parse_int();
        }
      }
    }
    if (!exponent) return base;
    if (special_ && special_->begin == begin) special_->combined = true;
    Unit u;
    u.scale = std::pow(base.scale, *exponent);
    u.dim = pow(base.dim, *exponent);
    return checked(u, exp_col);
  }

  // Signed integer exponent; at most kMaxExponent in magnitude.
  int parse_int() {
    const std::size_t begin = pos_;
    int sign = 1;
    if (peek() == '+' || peek() == '-') {
      if (peek() == '-') sign = -1;
      ++pos_;
    }
    if (!is_digit(peek())) fail("expected an integer exponent", pos_);
    long long value = 0;
    while (is_digit(peek())) {
      value = value * 10 + (peek() - '0');
      if (value > kMaxExponent) fail("exponent too large (limit " + std::to_string(kMaxExponent) + ")", begin);
      ++pos_;
    }
    if (peek() == '.' && pos_ + 1 < text_.size() && is_digit(text_[pos_ + 1]))
      fail("exponents must be integers", begin);
    return sign * static_cast<int>(value);
  }

  Unit parse_factor(int depth, bool& is_name) {
    is_name = false;
    const std::size_t begin = pos_;
    if (at_end()) fail("expected a unit", pos_);
    const char c = peek();
    if (c == '(') {
      if (depth >= kMaxDepth) fail("parentheses nested too deeply", pos_);
      ++pos_;
      skip_space();
      if (peek() == ')') fail("empty parentheses", begin);
      Unit inner = parse_product(depth + 1);
      skip_space();
      if (peek() != ')') {
        if (at_end()) fail("missing ')' to close this '('", begin);
        fail("expected ')' but found " + describe_at(pos_), pos_);
      }
      ++pos_;
      return inner;
    }
    if (is_digit(c)) {
      while (is_digit(peek()) || peek() == '.') ++pos_;
      if (text_.substr(begin, pos_ - begin) != "1")
        fail("only the number 1 may appear in a unit (as in '1/s'); exponents are written 'm3' or "
             "'m^3'",
             begin);
      return Unit{};
    }
    if (c == ')') fail("unbalanced ')': no matching '('", pos_);
    if (!(is_ascii_letter(c) || c == '_' || c == '%' || name_symbol_length(rest()) > 0))
      fail("expected a unit but found " + describe_at(pos_), pos_);

    is_name = true;
    if (c == '%') {
      ++pos_;
    } else {
      while (!at_end()) {
        if (is_ascii_letter(peek()) || peek() == '_') ++pos_;
        else if (std::size_t n = name_symbol_length(rest())) pos_ += n;
        else break;
      }
    }
    std::string name(text_.substr(begin, pos_ - begin));
    const Table& table = unit_table();
    // "bar(a)", "kPa(g)", also "bar (g)": absorb the suffix only when it forms
    // a known unit, so that "(" keeps its grouping meaning everywhere else.
    // Without this, "2 bar (g)" would silently parse as bar times gram.
    std::size_t after = pos_;
    while (after < text_.size() && is_space(text_[after])) ++after;
    for (const char* suffix : {"(a)", "(g)"}) {
      if (text_.substr(after).starts_with(suffix) && table.contains(name + suffix)) {
        name += suffix;
        pos_ = after + 3;
        break;
      }
    }
    // "6 bar g", "6 bar gauge", "6 bar abs": a separate word after a pressure
    // unit names its reference (bar times gram would be no pressure at all).
    if (after > pos_) {
      std::size_t word_end = after;
      while (word_end < text_.size() && (is_ascii_letter(text_[word_end]) || text_[word_end] == '_')) ++word_end;
      const std::string_view word = text_.substr(after, word_end - after);
      const char* suffix = word == "g" || word == "gauge"                    ? "g"
                           : word == "a" || word == "abs" || word == "absolute" ? "_abs"
                                                                                : nullptr;
      if (suffix && table.contains(name + "_abs") && table.contains(name + suffix)) {
        name += suffix;
        pos_ = word_end;
      }
    }
    const auto it = table.find(name);
    if (it == table.end()) unknown_unit(name, begin);
    const Unit& u = it->second;
    if (u.affine()) {
      if (!special_) {
        special_ = Special{name, begin, pos_, u.gauge};
        special_unit_ = u;
      } else {
        special_->combined = true;  // two special units: never valid
      }
    }
    // Affine/gauge offsets are dropped while combining; if the expression is
    // more than this token, parse_whole_unit() rejects it anyway.
    return Unit{u.scale, 0, u.dim};
  }

  [[noreturn]] void unknown_unit(const std::string& name, std::size_t column) {
    // Peek at an attached exponent so "Nm3" gets the normal-cubic-metre hint.
    int exponent = 0;
    if (is_digit(peek())) exponent = peek() - '0';
    std::string message = "unknown unit '" + name + "'";
    if (std::string hint = hint_for(name, exponent); !hint.empty()) {
      message += ": " + hint;
    } else if (auto matches = close_matches(name); !matches.empty()) {
      message += "; did you mean ";
      for (std::size_t i = 0; i < matches.size(); ++i) {
        if (i > 0) message += i + 1 == matches.size() ? " or " : ", ";
        message += "'" + matches[i] + "'";
      }
      message += "?";
    }
    fail(message, column);
  }

  std::string_view text_;
  std::size_t pos_;
  std::optional<Special> special_;
  Unit special_unit_;
};

// The unit that `text` names from `pos` on. Each run of a study elaborates
// its netlist again and meets the same few unit texts thousands of times:
// what parsed is remembered per thread (an error is thrown each time, with
// its column in `text`).
Unit whole_unit_from(std::string_view text, std::size_t pos) {
  thread_local std::unordered_map<std::string, Unit> parsed;
  const std::string key(text.substr(pos));
  if (const auto it = parsed.find(key); it != parsed.end()) return it->second;
  const Unit unit = Parser(text, pos).parse_whole_unit();
  constexpr std::size_t kMaxRemembered = 4096;  // a bound for hostile inputs
  if (parsed.size() < kMaxRemembered) parsed.emplace(key, unit);
  return unit;
}

}  // namespace

// ---------------------------------------------------------------------------
// Public API
// ---------------------------------------------------------------------------

Unit parse_unit(std::string_view text) { return whole_unit_from(text, 0); }

Dimension dimension_of(std::string_view unit_text) { return parse_unit(unit_text).dim; }

double to_si(const Unit& unit, double value, double ambient_pressure_pa) {
  double si = unit.scale * value + unit.offset;
  if (unit.gauge) {
    if (!std::isfinite(ambient_pressure_pa))
      throw std::invalid_argument("pneumo::units: ambient pressure must be finite");
    si += ambient_pressure_pa;
  }
  return si;
}

Quantity parse_quantity(std::string_view text, double ambient_pressure_pa) {
  Parser diag(text, 0);  // only used for uniform error messages
  std::size_t pos = 0;
  while (pos < text.size() && is_space(text[pos])) ++pos;
  if (pos == text.size()) diag.fail("empty quantity: expected a number, e.g. '5 bar'", pos);

  // Scan the number ourselves: std::from_chars is locale independent but
  // accepts "inf"/"nan" and no leading '+', neither of which we want.
  const std::size_t number_begin = pos;
  bool negative = false;
  if (text[pos] == '+' || text[pos] == '-') {
    negative = text[pos] == '-';
    ++pos;
  }
  const std::size_t mantissa_begin = pos;
  std::size_t digits = 0;
  while (pos < text.size() && is_digit(text[pos])) ++pos, ++digits;
  if (pos < text.size() && text[pos] == '.') {
    ++pos;
    while (pos < text.size() && is_digit(text[pos])) ++pos, ++digits;
  }
  if (digits == 0) {
    if (pos > number_begin) diag.fail("malformed number", number_begin);
    diag.fail("expected a number at the start of the quantity, e.g. '5 bar', but found " +
                  diag.describe_at(number_begin),
              number_begin);
  }
  // An 'e' is an exponent only if digits follow; otherwise it starts the unit.
  if (pos < text.size() && (text[pos] == 'e' || text[pos] == 'E')) {
    std::size_t p = pos + 1;
    if (p < text.size() && (text[p] == '+' || text[p] == '-')) ++p;
    if (p < text.size() && is_digit(text[p])) {
      pos = p;
      while (pos < text.size() && is_digit(text[pos])) ++pos;
    }
  }
  if (pos < text.size() && (text[pos] == '.' || is_digit(text[pos])))
    diag.fail("malformed number", number_begin);
  if (pos < text.size() && text[pos] == ',')
    diag.fail("malformed number: use '.' as the decimal separator", pos);

  double value = 0;
  const auto [end, ec] = std::from_chars(text.data() + mantissa_begin, text.data() + pos, value);
  if (ec == std::errc::result_out_of_range) diag.fail("number out of range", number_begin);
  if (ec != std::errc() || end != text.data() + pos) diag.fail("malformed number", number_begin);
  if (negative) value = -value;

  std::size_t unit_begin = pos;
  while (unit_begin < text.size() && is_space(text[unit_begin])) ++unit_begin;
  Quantity q{value, {}, false, false};
  if (unit_begin < text.size()) {
    const Unit unit = whole_unit_from(text, pos);
    q.si_value = to_si(unit, value, ambient_pressure_pa);
    q.dim = unit.dim;
    q.had_unit = true;
    q.gauge = unit.gauge;
  }
  if (!std::isfinite(q.si_value)) diag.fail("value out of range after conversion to SI units", number_begin);
  return q;
}

std::string si_unit_name(Dimension dim) {
  if (dim == dims::pressure) return "Pa";
  if (dim == dims::force) return "N";
  if (dim == dims::energy) return "J";
  if (dim == dims::power) return "W";
  if (dim == dims::volume) return "m3";
  if (dim == dims::area) return "m2";
  if (dim == dims::velocity) return "m/s";
  if (dim == dims::mass_flow) return "kg/s";
  if (dim == dims::volume_flow) return "m3/s";
  if (dim == dims::density) return "kg/m3";
  if (dim == dims::sonic_conductance) return "m3/(s*Pa)";
  return dim.to_string();
}

std::string format_si(double si_value, Dimension dim) {
  // Shortest round-trip digits; fixed notation for "everyday" magnitudes
  // (so 5e5 Pa prints as "500000"), scientific for very small/large ones.
  char buf[64];
  std::string number;
  if (!std::isfinite(si_value) || si_value == 0) {
    number = std::isnan(si_value) ? "nan" : std::isinf(si_value) ? (si_value < 0 ? "-inf" : "inf") : "0";
  } else {
    const double mag = std::fabs(si_value);
    const auto fmt = (mag >= 1e-4 && mag < 1e15) ? std::chars_format::fixed : std::chars_format::scientific;
    const auto res = std::to_chars(buf, buf + sizeof buf, si_value, fmt);
    number.assign(buf, res.ptr);
  }
  if (dim.dimensionless()) return number;
  return number + " " + si_unit_name(dim);
}

DisplayUnit display_unit(std::string_view unit_text, Dimension dim, double ambient_pressure_pa) {
  if (unit_text.empty()) return {si_unit_name(dim), 1.0, 0.0};
  const Unit u = parse_unit(unit_text);
  if (!(u.dim == dim))
    throw DimensionMismatch("'" + std::string(unit_text) + "' measures " + si_unit_name(u.dim) + ", not " + si_unit_name(dim));
  return {std::string(unit_text), u.scale, u.offset + (u.gauge ? ambient_pressure_pa : 0.0)};
}

const std::vector<NamedQuantity>& named_quantities() {
  static const std::vector<NamedQuantity> q{
      {"pressure", dims::pressure},   {"length", dims::length},       {"temperature", dims::temperature},
      {"time", dims::time},           {"velocity", dims::velocity},   {"acceleration", dims::acceleration},
      {"force", dims::force},         {"mass", dims::mass},           {"area", dims::area},
      {"volume", dims::volume},       {"mass_flow", dims::mass_flow}, {"volume_flow", dims::volume_flow},
      {"energy", dims::energy},       {"power", dims::power}};
  return q;
}

std::string difference_unit(std::string_view unit_text) {
  if (unit_text.empty() || !parse_unit(unit_text).gauge) return std::string(unit_text);
  for (const char* suffix : {"(g)", "_rel", "_g", "g"})  // the spellings unit_table() gives gauge units
    if (unit_text.ends_with(suffix)) return std::string(unit_text.substr(0, unit_text.size() - std::strlen(suffix)));
  return std::string(unit_text);
}

std::string habitual_unit_if_implausible(double v, Dimension dim) {
  const double a = std::abs(v);
  if (a == 0.0 || !std::isfinite(v)) return "";  // 0 is 0 in every unit
  if (dim == dims::length) return a > 10.0 ? "mm" : "";                 // beyond 10 m
  if (dim == dims::pressure) return a < 1000.0 ? "bar" : "";            // below 10 mbar
  if (dim == dims::temperature) return v < 100.0 ? "degC" : "";         // below -173 degC
  if (dim == dims::area) return a > 1.0 ? "mm2" : "";                   // beyond 1 m2
  if (dim == dims::volume) return a > 1.0 ? "L" : "";                   // beyond 1000 L
  if (dim == dims::sonic_conductance) return a > 1e-5 ? "dm3/(s*bar)" : "";  // beyond 1000 dm3/(s*bar)
  return "";
}

std::vector<std::string> known_unit_names() {
  std::vector<std::string> names;
  for (const auto& [name, unit] : unit_table()) names.push_back(name);
  return names;
}

}  // namespace pneumo::units
