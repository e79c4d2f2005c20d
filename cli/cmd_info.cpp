#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "core/bounds.hpp"
#include "core/io/bundled_characters.hpp"

namespace cli {

void add_info_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("info", "print a JSON summary of a character file (or a bundled "
                                         "character name)");
  auto file = std::make_shared<std::string>();
  cmd->add_option("FILE", *file, "character file (.urdf, .json) or bundled name")->required();
  cmd->callback([file] {
    core::io::LoadResult loaded;
    try {
      loaded = core::io::load_character(*file);
    } catch (const core::ModelError& e) {
      std::cerr << "pindrag info: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
    const core::Model& m = *loaded.model;
    std::map<std::string, int> by_type;
    for (int i = 1; i < m.njoints; ++i) ++by_type[core::to_string(m.joint_type[i])];
    nlohmann::json out;
    out["name"] = m.name;
    out["links"] = m.nlinks();
    out["joints"] = by_type;
    out["nq"] = m.nq;
    out["nv"] = m.nv;
    out["total_mass"] = m.total_mass();
    out["height"] = core::neutral_height(m);
    out["root"] = m.link_name[1];
    out["root_joint"] = core::to_string(m.joint_type[1]);
    out["warnings"] = loaded.warnings;
    std::cout << out.dump(2) << "\n";
  });
}

}  // namespace cli
