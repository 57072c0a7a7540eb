#pragma once

#include <CLI/CLI.hpp>

namespace pneumo::cli {

// `pneumo optimize`; sets `status` when it ran.
void add_optimize_command(CLI::App& app, int& status);

}  // namespace pneumo::cli
