// The `pneumo diagnose` subcommand (sim-to-real gap diagnosis).
#pragma once

#include <CLI/CLI.hpp>

namespace pneumo {
CLI::App* add_diagnose_command(CLI::App& app);
int run_diagnose_command();
}
