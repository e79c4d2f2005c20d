// pindrag: one executable, one subcommand per job over the same libraries.
#include <CLI/CLI.hpp>

#include "cli/commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"pindrag: pin-and-drag posing and animation of characters"};
  app.require_subcommand(1);
  cli::add_info_command(app);
  cli::add_character_command(app);
  cli::add_solve_command(app);
  cli::add_bench_command(app);
  cli::add_dynamics_command(app);
  cli::add_serve_command(app);
  cli::add_convert_command(app);
  cli::add_edit_command(app);
  cli::add_thumbnail_command(app);
  cli::add_simulate_command(app);
  cli::add_fit_command(app);
  cli::add_retarget_command(app);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
