#include <iostream>
#include <unistd.h>

#include "cli/accuracy_report.hpp"
#include "cli/commands.hpp"

namespace cli {

void add_bench_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("bench", "measure what accuracy costs in time: sweep the IK settings over "
                                          "scripted drags and write a report with plots");
  auto dir = std::make_shared<std::string>();
  cmd->add_option("--report", *dir, "folder for accuracy-vs-time.md and its SVG plots")->required();
  cmd->callback([dir] {
    const bool tty = isatty(STDERR_FILENO);
    const auto results = run_accuracy_sweep([tty](int done, int total) {
      if (tty) std::cerr << "\r[" << std::string(done * 40 / total, '#') << std::string(40 - done * 40 / total, ' ') << "] "
                         << done << "/" << total << std::flush;
    });
    if (tty) std::cerr << "\n";
    std::cout << write_accuracy_report(results, *dir) << "\n";
  });
}

}  // namespace cli
