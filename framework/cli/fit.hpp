// `pneumo fit friction|throttle`: identification from rig data
// (framework/fit). Hooked into main.cpp by add_fit_command().
#pragma once

#include <CLI/CLI.hpp>

#include <memory>

namespace pneumo::cli {

class FitCommand {
 public:
  virtual ~FitCommand() = default;
  virtual bool selected() const = 0;
  // Exit status: 0 success, 1 the fit did not converge; throws InputError for bad input.
  virtual int run() = 0;
};

std::unique_ptr<FitCommand> add_fit_command(CLI::App& app);

}  // namespace pneumo::cli
