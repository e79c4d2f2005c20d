#include <fstream>
#include <iostream>

#include "cli/commands.hpp"
#include "cli/json_fields.hpp"
#include "cli/simulate_scene.hpp"

namespace cli {

void add_simulate_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("simulate",
                                 "simulate a scene file (bodies, ground, effects) and print the "
                                 "recorded frames and stage counts (docs/simulation.md)");
  auto scene = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  cmd->add_option("--scene", *scene, "scene JSON file")->required();
  cmd->add_option("-o,--output", *out, "write the result here instead of standard output");
  cmd->callback([scene, out] {
    try {
      SimulationRun run = read_simulation_scene(read_json_file(*scene));
      const nlohmann::json result = run_simulation(run);
      if (out->empty()) {
        std::cout << result.dump(1) << "\n";
      } else {
        std::ofstream file(*out);
        file << result.dump(1) << "\n";
        if (!file) {
          std::cerr << "pindrag simulate: " << *out << ": cannot write the file\n";
          throw CLI::RuntimeError(1);
        }
      }
      std::cerr << "simulated " << run.world->time() << " s in steps of "
                << run.world->settings().step * 1e3 << " ms; median "
                << result["us_per_step"].get<double>() << " µs per step; stages:";
      for (const auto& [name, calls] : result["stages"].items()) {
        std::cerr << " " << name << " " << calls.get<std::uint64_t>();
      }
      std::cerr << "\n";
    } catch (const RequestError& e) {
      std::cerr << "pindrag simulate: " << *scene << ": " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace cli
