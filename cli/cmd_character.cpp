// pindrag character: writes the generated human figure (core/human_figure.hpp) as character JSON.
#include <cmath>
#include <exception>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include "cli/commands.hpp"
#include "core/human_figure.hpp"
#include "io/character_json.hpp"

namespace cli {

namespace {

std::string number(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

// a validator that accepts a finite number in [lo, hi] and names the quantity and its unit
CLI::Validator in_range(const std::string& what, double lo, double hi, const std::string& unit) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double x = 0;
        std::size_t used = 0;
        try {
          x = std::stod(text, &used);
        } catch (const std::exception&) {
          return what + " must be a number (got '" + text + "')";
        }
        if (used != text.size() || !std::isfinite(x)) {
          return what + " must be a finite number (got '" + text + "')";
        }
        if (x < lo || x > hi) {
          return what + " must be between " + number(lo) + " and " + number(hi) + " " + unit +
                 " (got " + text + ")";
        }
        return {};
      },
      "in [" + number(lo) + ", " + number(hi) + "] " + unit);
}

}  // namespace

void add_character_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "character",
      "generate the human figure for a stature and body mass (de Leva 1996 segments, clinical "
      "joint ranges; docs/human-figure.md) and write it as character JSON");
  auto options = std::make_shared<core::HumanFigureOptions>();
  auto output = std::make_shared<std::string>();
  cmd->add_option("--height", options->height, "standing height, sole to vertex (m)")
      ->check(in_range("height", core::kHumanMinHeight, core::kHumanMaxHeight, "m"))
      ->capture_default_str();
  cmd->add_option("--mass", options->mass, "body mass (kg)")
      ->check(in_range("mass", core::kHumanMinMass, core::kHumanMaxMass, "kg"))
      ->capture_default_str();
  cmd->add_option("--dof", options->dof,
                  "48 (posing figure) or 34 (HeiMan-like figure of Felis et al.)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            if (text == "34" || text == "48") return {};
            return "dof must be 34 or 48 (got '" + text + "')";
          },
          "34|48"))
      ->capture_default_str();
  cmd->add_option("-o,--output", *output, "character JSON file to write")->required();
  cmd->callback([options, output] {
    try {
      const auto model = core::build_human_figure(*options);
      io::save_character_json_file(*model, *output);
      std::cout << "wrote " << *output << ": " << model->name << ", " << model->nv << " DOF, "
                << model->nlinks() << " links, " << number(options->height) << " m, "
                << number(model->total_mass()) << " kg\n";
    } catch (const std::exception& e) {
      std::cerr << "pindrag character: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace cli
