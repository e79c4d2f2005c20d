// `pindrag bench --report DIR`, the simulation page: integrator × step size against the book's
// box tests (Yamane §6.4): how deep a dropped box sinks, how much energy it gains, how far a
// sliding box stops from where Coulomb friction stops it, and what each costs per simulated
// second. Writes DIR/simulation-accuracy.md with SVG plots.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "sim/settings.hpp"

namespace cli {

struct IntegratorResult {
  sim::Integrator integrator = sim::Integrator::kImplicit;
  double step = 0;            // s
  bool finite = true;         // false: the simulation blew up
  double penetration = 0;     // deepest point of the dropped box (m)
  double energy_gain = 0;     // largest energy above the start while it falls and settles (J)
  double friction_error = 0;  // |stop distance − Coulomb's| / Coulomb's, sliding box
  double us_per_second = 0;   // CPU time per simulated second of the dropped box (µs)
  bool front_penetration = false, front_friction = false;
};

std::vector<IntegratorResult> run_integrator_sweep(const std::function<void(int, int)>& progress);

/// Writes DIR/simulation-accuracy.md and its plots; returns the page's path.
std::string write_integrator_report(const std::vector<IntegratorResult>& results,
                                    const std::string& dir);

}  // namespace cli
