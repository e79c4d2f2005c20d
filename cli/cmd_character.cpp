#include "cli/commands.hpp"

namespace cli {
void add_character_command(CLI::App& app) {
  app.add_subcommand("character", "generate a human figure");
}
}  // namespace cli
