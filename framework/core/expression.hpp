// Arithmetic expressions over named values: numbers, names (letters, digits,
// '_' and '.', e.g. `t_done` or `cylinder.cap_impact`), + - * /, unary minus
// and plus, and parentheses. Parsed once; evaluated with a lookup for the names. Used
// by netlist metrics (`expr: t_done - t_start`) and the diagnosis catalogue's
// ${...} parameter arithmetic.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "framework/core/units.hpp"

namespace pneumo {

class Expression {
 public:
  // Throws ExpressionError naming the offending column (0-based).
  // Longer expressions, or parentheses and signs nested deeper, are refused:
  // the limits keep parsing and evaluation bounded in memory and stack.
  static constexpr std::size_t kMaxLength = 100000;  // characters
  static constexpr std::size_t kMaxDepth = 200;      // nested parentheses and signs
  explicit Expression(const std::string& text);
  double evaluate(const std::function<double(const std::string&)>& lookup) const;
  // The dimension of the value, given each name's. A number takes the
  // dimension of what it is added to (`t_done - 0.1`) and is dimensionless in
  // a product; nullopt when a sum mixes dimensions (a time plus a pressure).
  std::optional<units::Dimension> dimension(
      const std::function<units::Dimension(const std::string&)>& dimension_of) const;
  std::vector<std::string> names() const { return names_; }  // in order of first use (a copy: safe on temporaries)

  struct Node;

 private:
  std::shared_ptr<const std::vector<Node>> program_;  // postfix
  std::vector<std::string> names_;
};

struct ExpressionError : std::runtime_error {
  std::size_t column;
  ExpressionError(const std::string& what, std::size_t column) : std::runtime_error(what), column(column) {}
};

}  // namespace pneumo
