#include "cli/commands.hpp"

namespace cli {
void add_info_command(CLI::App& app) { app.add_subcommand("info", "summary of a character file"); }
}  // namespace cli
