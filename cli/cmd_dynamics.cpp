#include <iostream>

#include "cli/commands.hpp"
#include "cli/dynamics_state.hpp"
#include "cli/json_fields.hpp"
#include "core/model_edit.hpp"
#include "io/bundled_characters.hpp"

namespace cli {

void add_dynamics_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "dynamics",
      "print the RNEA torques, ABA accelerations, mass matrix and bias forces of one "
      "state given by joint name (docs/dynamics.md)");
  auto file = std::make_shared<std::string>();
  auto state = std::make_shared<std::string>();
  auto fixed_base = std::make_shared<bool>(false);
  cmd->add_option("FILE", *file, "character file (.urdf, .json) or bundled name")->required();
  cmd->add_option("--state", *state,
                  "state JSON: {\"q\": {...}, \"v\": {...}, \"a\": {...}, "
                  "\"tau\": {...}} keyed by joint name")
      ->required();
  cmd->add_flag("--fixed-base", *fixed_base, "weld the root link to the world");
  cmd->callback([file, state, fixed_base] {
    std::shared_ptr<const core::Model> model;
    try {
      io::LoadOptions options;
      if (*fixed_base) options.root = io::RootJoint::kFixed;
      model = io::load_character(*file, options).model;
      // a loader that ignores the option (a generated or native character): weld it here
      if (*fixed_base) model = core::weld_root(model);
    } catch (const core::ModelError& e) {
      std::cerr << "pindrag dynamics: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
    try {
      std::cout << run_dynamics(*model, read_json_file(*state)).dump(1) << "\n";
    } catch (const RequestError& e) {
      std::cerr << "pindrag dynamics: " << *state << ": " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace cli
