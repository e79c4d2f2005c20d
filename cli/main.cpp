// pindrag: one executable, one subcommand per batch job over the same libraries.
#include <CLI/CLI.hpp>
#include <iostream>

int main(int argc, char** argv) {
  CLI::App app{"pindrag: pin-and-drag posing and animation of characters"};
  app.require_subcommand(1);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
