#include "framework/core/expression.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <optional>

namespace pneumo {

// One step of the postfix program: push a number or a named value, or apply
// an operator to the values on top of the stack. A flat program (no tree)
// keeps evaluation and destruction free of recursion, whatever the length.
struct Expression::Node {
  char op = 0;  // 0 number, 'n' name, '+', '-', '*', '/', 'u' (unary minus)
  double number = 0.0;
  std::size_t name = 0;  // index into names_
  std::size_t column = 0;  // of the operator, for messages
};

namespace {

using Program = std::vector<Expression::Node>;

// Recursive descent emitting postfix: sum := product {(+|-) product};
// product := unary {(*|/) unary}; unary := (-|+) unary | atom;
// atom := number | name | ( sum ). Sums and products loop, so only
// parentheses and signs recurse, and their nesting is bounded.
class Parser {
 public:
  Parser(const std::string& s, std::vector<std::string>& names, Program& out) : s_(s), names_(names), out_(out) {}

  void parse() {
    if (s_.size() > Expression::kMaxLength)
      throw ExpressionError("the expression has " + std::to_string(s_.size()) + " characters; at most " +
                                std::to_string(Expression::kMaxLength) + " are accepted (split it into several metrics)",
                            Expression::kMaxLength);
    sum();
    skip();
    if (i_ < s_.size()) throw ExpressionError("unexpected '" + std::string(1, s_[i_]) + "'", i_);
  }

 private:
  // Counts nesting (parentheses and signs) while a nested part is parsed.
  struct Deeper {
    explicit Deeper(Parser& p) : p(p) {
      if (++p.depth_ > Expression::kMaxDepth)
        throw ExpressionError("parentheses and signs are nested more than " + std::to_string(Expression::kMaxDepth) +
                                  " deep here",
                              p.i_);
    }
    ~Deeper() { --p.depth_; }
    Parser& p;
  };

  std::size_t column_of_next() {
    skip();
    return i_;
  }
  void skip() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool take(char c) {
    skip();
    if (i_ < s_.size() && s_[i_] == c) return ++i_, true;
    return false;
  }
  void emit(char op, std::size_t column) { out_.push_back({op, 0.0, 0, column}); }
  void sum() {
    product();
    for (;;) {
      const std::size_t at = column_of_next();
      if (take('+')) product(), emit('+', at);
      else if (take('-')) product(), emit('-', at);
      else return;
    }
  }
  void product() {
    unary();
    for (;;) {
      const std::size_t at = column_of_next();
      if (take('*')) unary(), emit('*', at);
      else if (take('/')) unary(), emit('/', at);
      else return;
    }
  }
  void unary() {
    if (take('-')) {
      Deeper d(*this);
      unary();
      emit('u', 0);
    } else if (take('+')) {
      Deeper d(*this);
      unary();
    } else {
      atom();
    }
  }
  void atom() {
    skip();
    if (i_ >= s_.size()) throw ExpressionError("expression ends early: a value is expected here", i_);
    if (take('(')) {
      Deeper d(*this);
      sum();
      if (!take(')')) throw ExpressionError("missing ')'", i_);
      return;
    }
    const char c = s_[i_];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      char* end = nullptr;
      const double v = std::strtod(s_.c_str() + i_, &end);
      const auto used = static_cast<std::size_t>(end - (s_.c_str() + i_));
      if (used == 0) throw ExpressionError("cannot read a number here", i_);
      i_ += used;
      out_.push_back({0, v, 0, 0});
      return;
    }
    if (!(std::isalpha(static_cast<unsigned char>(c)) || c == '_'))
      throw ExpressionError("unexpected '" + std::string(1, c) + "'", i_);
    const std::size_t start = i_;
    while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '_' || s_[i_] == '.')) ++i_;
    const std::string name = s_.substr(start, i_ - start);
    auto it = std::find(names_.begin(), names_.end(), name);
    const auto index = static_cast<std::size_t>(it - names_.begin());
    if (it == names_.end()) names_.push_back(name);
    out_.push_back({'n', 0.0, index, 0});
  }

  const std::string& s_;
  std::vector<std::string>& names_;
  Program& out_;
  std::size_t i_ = 0;
  std::size_t depth_ = 0;
};

// Refuses a division by a part that is 0 whatever the names' values
// (`x / 0`, `x / (2 - 2)`): a metric that is always infinite or NaN.
void check_constant_divisors(const Program& program) {
  std::vector<std::optional<double>> stack;  // the value of a constant part
  for (const auto& n : program) {
    if (n.op == 0) {
      stack.push_back(n.number);
    } else if (n.op == 'n') {
      stack.push_back(std::nullopt);
    } else if (n.op == 'u') {
      if (stack.back()) stack.back() = -*stack.back();
    } else {
      const auto b = stack.back();
      stack.pop_back();
      auto& a = stack.back();
      if (n.op == '/' && b && *b == 0.0)
        throw ExpressionError("division by zero: the divisor after this '/' is always 0", n.column);
      if (!a || !b) a = std::nullopt;
      else if (n.op == '+') *a += *b;
      else if (n.op == '-') *a -= *b;
      else if (n.op == '*') *a *= *b;
      else *a /= *b;
    }
  }
}

}  // namespace

Expression::Expression(const std::string& text) {
  auto program = std::make_shared<Program>();
  Parser(text, names_, *program).parse();
  check_constant_divisors(*program);
  program_ = std::move(program);
}

double Expression::evaluate(const std::function<double(const std::string&)>& lookup) const {
  std::vector<double> stack;
  stack.reserve(program_->size());
  for (const Node& n : *program_) {
    if (n.op == 0) {
      stack.push_back(n.number);
    } else if (n.op == 'n') {
      stack.push_back(lookup(names_[n.name]));
    } else if (n.op == 'u') {
      stack.back() = -stack.back();
    } else {
      const double b = stack.back();
      stack.pop_back();
      double& a = stack.back();
      switch (n.op) {
        case '+': a += b; break;
        case '-': a -= b; break;
        case '*': a *= b; break;
        default: a /= b; break;
      }
    }
  }
  return stack.back();
}

std::optional<units::Dimension> Expression::dimension(
    const std::function<units::Dimension(const std::string&)>& dimension_of) const {
  struct Term {
    units::Dimension dim;
    bool number;  // a bare number: fits any dimension in a sum
  };
  std::vector<Term> stack;
  for (const Node& n : *program_) {
    if (n.op == 0) {
      stack.push_back({{}, true});
    } else if (n.op == 'n') {
      stack.push_back({dimension_of(names_[n.name]), false});
    } else if (n.op != 'u') {
      const Term b = stack.back();
      stack.pop_back();
      Term& a = stack.back();
      if (n.op == '*' || n.op == '/') {
        a = {n.op == '*' ? a.dim * b.dim : a.dim / b.dim, a.number && b.number};
      } else if (a.number) {
        a = b;
      } else if (!b.number && !(a.dim == b.dim)) {
        return std::nullopt;
      }
    }
  }
  return stack.back().dim;
}

}  // namespace pneumo
