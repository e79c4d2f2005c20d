#include <unistd.h>

#include <iostream>

#include "cli/accuracy_report.hpp"
#include "cli/commands.hpp"
#include "cli/sim_accuracy_report.hpp"

namespace cli {

void add_bench_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("bench",
                                 "measure what accuracy costs in time: sweep the IK settings over "
                                 "scripted drags, and the integrators over the book's "
                                 "box tests, and write reports with plots");
  auto dir = std::make_shared<std::string>();
  cmd->add_option("--report", *dir, "folder for accuracy-vs-time.md and its SVG plots")->required();
  cmd->callback([dir] {
    const bool tty = isatty(STDERR_FILENO);
    const auto results = run_accuracy_sweep([tty](int done, int total) {
      if (tty)
        std::cerr << "\r[" << std::string(done * 40 / total, '#')
                  << std::string(40 - done * 40 / total, ' ') << "] " << done << "/" << total
                  << std::flush;
    });
    if (tty) std::cerr << "\n";
    std::cout << write_accuracy_report(results, *dir) << "\n";
    const auto integrators = run_integrator_sweep([tty](int done, int total) {
      if (tty) std::cerr << "\rintegrators " << done << "/" << total << std::flush;
    });
    if (tty) std::cerr << "\n";
    std::cout << write_integrator_report(integrators, *dir) << "\n";
  });
}

}  // namespace cli
