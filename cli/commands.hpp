// Subcommands of the pindrag executable; each lives in its own cmd_<name>.cpp.
#pragma once

#include <CLI/CLI.hpp>

namespace cli {

/// Each add_* registers one subcommand and its callback on the app.
void add_info_command(CLI::App& app);
void add_character_command(CLI::App& app);
void add_solve_command(CLI::App& app);
void add_bench_command(CLI::App& app);
void add_dynamics_command(CLI::App& app);
void add_serve_command(CLI::App& app);
void add_convert_command(CLI::App& app);
void add_edit_command(CLI::App& app);
void add_thumbnail_command(CLI::App& app);
void add_simulate_command(CLI::App& app);
void add_fit_command(CLI::App& app);
void add_retarget_command(CLI::App& app);

}  // namespace cli
