// `pindrag bench --report DIR`: what accuracy costs in time. Sweeps the solver settings that
// trade one for the other (iterations per frame, damping and its schedule, gains) over scripted
// drags on the human figure and writes DIR/accuracy-vs-time.md with SVG plots.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "ik/solver.hpp"

namespace cli {

/// One scripted drag: a name and a frame count; the scene is built by the report.
struct Scenario {
  std::string name;
  std::string description;
  int frames = 120;
  /// False when the drag cannot be reached with the pins held: then the pins give way by design
  /// (the drag is the top priority, digest §4 #3) and their drift is not counted as pin drift.
  bool reachable = true;
};

/// The measured outcome of one setting over all scenarios.
struct SettingResult {
  std::string label;
  ik::SolverSettings settings;
  double median_us = 0;           // median wall time of one frame (best of the repetitions)
  double drag_error = 0;          // RMS over frames and scenarios (m)
  double pin_drift = 0;           // largest pin position error in reachable scenarios (m)
  double limit_violation = 0;     // largest range violation (rad)
  double joint_speed = 0;         // largest joint speed (rad/s)
  bool pareto_time_drag = false;  // on the front of (time, drag error)
  bool pareto_time_pins = false;  // on the front of (time, pin drift)
};

std::vector<Scenario> report_scenarios();

/// Runs every setting of the sweep over every scenario. `progress(done, total)` is called
/// after each setting.
std::vector<SettingResult> run_accuracy_sweep(const std::function<void(int, int)>& progress);

/// Writes DIR/accuracy-vs-time.md and its SVG plots; returns the page's path.
std::string write_accuracy_report(const std::vector<SettingResult>& results,
                                  const std::string& dir);

}  // namespace cli
