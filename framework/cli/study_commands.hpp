// `pneumo sweep` and `pneumo sensitivity` (framework/study). main() adds them
// with add_study_commands(); after parsing, `status` holds the exit status
// if one of them ran (else -1).
#pragma once

#include <CLI/CLI.hpp>

namespace pneumo::cli {

void add_study_commands(CLI::App& app, int& status);

}  // namespace pneumo::cli
