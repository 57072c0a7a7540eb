#include "framework/core/expression.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>

namespace pneumo {

struct Expression::Node {
  char op = 0;  // 0 number, 'n' name, '+', '-', '*', '/', 'u' (unary minus)
  double number = 0.0;
  std::string name;
  std::shared_ptr<const Node> a, b;
};

namespace {

using NodePtr = std::shared_ptr<const Expression::Node>;

// Recursive descent: sum := product {(+|-) product}; product := unary {(*|/)
// unary}; unary := (-|+) unary | atom; atom := number | name | ( sum ).
class Parser {
 public:
  Parser(const std::string& s, std::vector<std::string>& names) : s_(s), names_(names) {}

  NodePtr parse() {
    NodePtr n = sum();
    skip();
    if (i_ < s_.size()) throw ExpressionError("unexpected '" + std::string(1, s_[i_]) + "'", i_);
    return n;
  }

 private:
  void skip() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool take(char c) {
    skip();
    if (i_ < s_.size() && s_[i_] == c) return ++i_, true;
    return false;
  }
  static NodePtr binary(char op, NodePtr a, NodePtr b) {
    auto n = std::make_shared<Expression::Node>();
    n->op = op, n->a = std::move(a), n->b = std::move(b);
    return n;
  }
  NodePtr sum() {
    NodePtr n = product();
    for (;;) {
      if (take('+')) n = binary('+', n, product());
      else if (take('-')) n = binary('-', n, product());
      else return n;
    }
  }
  NodePtr product() {
    NodePtr n = unary();
    for (;;) {
      if (take('*')) n = binary('*', n, unary());
      else if (take('/')) n = binary('/', n, unary());
      else return n;
    }
  }
  NodePtr unary() {
    if (take('-')) return binary('u', unary(), nullptr);
    if (take('+')) return unary();
    return atom();
  }
  NodePtr atom() {
    skip();
    if (i_ >= s_.size()) throw ExpressionError("expression ends early: a value is expected here", i_);
    if (take('(')) {
      NodePtr n = sum();
      if (!take(')')) throw ExpressionError("missing ')'", i_);
      return n;
    }
    auto n = std::make_shared<Expression::Node>();
    const char c = s_[i_];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      char* end = nullptr;
      n->number = std::strtod(s_.c_str() + i_, &end);
      const auto used = static_cast<std::size_t>(end - (s_.c_str() + i_));
      if (used == 0) throw ExpressionError("cannot read a number here", i_);
      i_ += used;
      return n;
    }
    if (!(std::isalpha(static_cast<unsigned char>(c)) || c == '_'))
      throw ExpressionError("unexpected '" + std::string(1, c) + "'", i_);
    const std::size_t start = i_;
    while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '_' || s_[i_] == '.')) ++i_;
    n->op = 'n';
    n->name = s_.substr(start, i_ - start);
    if (std::find(names_.begin(), names_.end(), n->name) == names_.end()) names_.push_back(n->name);
    return n;
  }

  const std::string& s_;
  std::vector<std::string>& names_;
  std::size_t i_ = 0;
};

double eval(const Expression::Node& n, const std::function<double(const std::string&)>& lookup) {
  switch (n.op) {
    case 'n': return lookup(n.name);
    case '+': return eval(*n.a, lookup) + eval(*n.b, lookup);
    case '-': return eval(*n.a, lookup) - eval(*n.b, lookup);
    case '*': return eval(*n.a, lookup) * eval(*n.b, lookup);
    case '/': return eval(*n.a, lookup) / eval(*n.b, lookup);
    case 'u': return -eval(*n.a, lookup);
    default: return n.number;
  }
}

}  // namespace

Expression::Expression(const std::string& text) { root_ = Parser(text, names_).parse(); }

double Expression::evaluate(const std::function<double(const std::string&)>& lookup) const {
  return eval(*root_, lookup);
}

}  // namespace pneumo
