// Errors that reach the user. Every error about user input carries where it
// came from (file:line:column), which component and which parameter, so that
// the message alone is enough to fix the netlist.
#pragma once

#include <stdexcept>
#include <string>

namespace pneumo {

// A position in an input file. line and column are 1-based; 0 means unknown.
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;

  bool known() const { return !file.empty(); }
  std::string to_string() const {
    if (file.empty()) return "<input>";
    if (line <= 0) return file;
    return file + ":" + std::to_string(line) + ":" + std::to_string(column);
  }
};

// An error in user input (netlist, command line, data file).
class InputError : public std::runtime_error {
 public:
  InputError(SourceLocation where, std::string component, std::string parameter,
             std::string message)
      : std::runtime_error(compose(where, component, parameter, message)),
        where_(std::move(where)),
        component_(std::move(component)),
        parameter_(std::move(parameter)),
        message_(std::move(message)) {}

  const SourceLocation& where() const { return where_; }
  const std::string& component() const { return component_; }
  const std::string& parameter() const { return parameter_; }
  const std::string& message() const { return message_; }

 private:
  static std::string compose(const SourceLocation& where, const std::string& component,
                             const std::string& parameter, const std::string& message) {
    std::string s = where.to_string() + ": error: ";
    if (!component.empty()) s += "component '" + component + "'";
    if (!parameter.empty()) s += (component.empty() ? "" : ", ") + std::string("parameter '") + parameter + "'";
    if (!component.empty() || !parameter.empty()) s += ": ";
    return s + message;
  }

  SourceLocation where_;
  std::string component_;
  std::string parameter_;
  std::string message_;
};

// The assembled system cannot be solved as posed (structurally singular,
// higher index, unbalanced component). Found before the solver runs.
class StructureError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The solver failed (step size too small, convergence failure, ...).
class SolverError : public std::runtime_error {
 public:
  SolverError(const std::string& what, double t) : std::runtime_error(what), t_(t) {}
  double time() const { return t_; }

 private:
  double t_;
};

}  // namespace pneumo
