#include <iostream>

#include "cli/commands.hpp"
#include "cli/json_fields.hpp"
#include "cli/solve_request.hpp"

namespace cli {

void add_solve_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("solve",
                                 "run the pin-and-drag IK headless on a request file "
                                 "and print per-frame errors and the final pose (docs/ik.md)");
  auto request = std::make_shared<std::string>();
  cmd->add_option("--request", *request, "request JSON file")->required();
  cmd->callback([request] {
    try {
      const nlohmann::json out = run_solve_request(read_json_file(*request));
      std::cout << out.dump(1) << "\n";
    } catch (const RequestError& e) {
      std::cerr << "pindrag solve: " << *request << ": " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace cli
