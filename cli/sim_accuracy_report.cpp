#include "cli/sim_accuracy_report.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "cli/svg_scatter.hpp"
#include "core/configuration.hpp"
#include "sim/props.hpp"
#include "sim/world.hpp"

namespace cli {

namespace {

constexpr sim::Integrator kIntegrators[] = {sim::Integrator::kImplicit,
                                            sim::Integrator::kSemiImplicit, sim::Integrator::kRk4};
constexpr double kSteps[] = {1e-4, 2.5e-4, 5e-4, 1e-3, 2e-3, 4e-3, 8e-3};

sim::Scene box_scene() {
  sim::Scene s;
  s.gravity = s.ground_contact = s.friction = true;
  return s;
}

// a 1 kg 0.2 × 0.1 × 0.3 m box dropped tilted from 0.5 m while moving sideways, 3 s
void drop_box(IntegratorResult& r) {
  sim::WorldSettings s;
  s.step = r.step;
  s.integrator = r.integrator;
  sim::World w(s);
  sim::PropShape shape;
  shape.size = core::Vector3(0.2, 0.1, 0.3);
  auto m = sim::make_prop("box", shape, 1.0);
  Eigen::VectorXd q = core::neutral_configuration(*m);
  q[1] = 0.5;
  core::set_quaternion_at(
      q, 3, core::Quaternion(Eigen::AngleAxisd(0.4, core::Vector3(1, 0.3, 0.2).normalized())));
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
  v[3] = 0.5;
  w.add_body("box", m, q, v);
  w.set_scene(box_scene());
  const double e0 = w.energy();
  const int steps = static_cast<int>(std::round(3.0 / r.step));
  double seconds = 0;
  for (int k = 0; k < steps; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    w.step();
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!w.body(0).q.allFinite() || !w.body(0).v.allFinite()) {
      r.finite = false;
      return;
    }
    for (const sim::ContactPoint& p : w.contact_points()) {
      r.penetration = std::max(r.penetration, p.depth);
    }
    r.energy_gain = std::max(r.energy_gain, w.energy() - e0);
  }
  r.us_per_second = seconds * 1e6 / 3.0;
}

// the 1 kg cube sliding at 1 m/s with (μS, μD) = (0.35, 0.25): Coulomb stops it after
// v0² / (2 μD g) = 0.204 m
void slide_box(IntegratorResult& r) {
  sim::WorldSettings s;
  s.step = r.step;
  s.integrator = r.integrator;
  s.contact.mu_static = 0.35;
  s.contact.mu_dynamic = 0.25;
  s.contact.kfp = 1000;
  s.contact.kfd = 700;
  sim::World w(s);
  sim::PropShape shape;
  shape.size = core::Vector3(0.2, 0.2, 0.2);
  auto m = sim::make_prop("box", shape, 1.0);
  Eigen::VectorXd q = core::neutral_configuration(*m);
  q[1] = 0.1 - 9.81 / s.contact.kp;
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
  v[3] = 1.0;
  w.add_body("box", m, q, v);
  w.set_scene(box_scene());
  const double coulomb = 1.0 / (2 * 0.25 * 9.81);
  w.advance(2.0);
  r.friction_error = w.body(0).q.allFinite() ? std::abs(w.body(0).q[0] - coulomb) / coulomb
                                             : std::numeric_limits<double>::infinity();
}

std::string cell(double v) {
  if (!std::isfinite(v)) return "—";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

void plot(const std::vector<IntegratorResult>& results,
          double IntegratorResult::*y,
          bool IntegratorResult::*front,
          const std::string& title,
          const std::string& y_label,
          const std::string& path) {
  ScatterPlot p;
  p.title = title;
  p.x_label = "CPU time per simulated second (µs)";
  p.y_label = y_label;
  for (sim::Integrator in : kIntegrators) p.series.push_back(sim::to_string(in));
  for (const IntegratorResult& r : results) {
    p.points.push_back({r.us_per_second, r.*y, static_cast<int>(r.integrator), r.*front});
  }
  write_scatter_svg(p, path);
}

}  // namespace

std::vector<IntegratorResult> run_integrator_sweep(const std::function<void(int, int)>& progress) {
  std::vector<IntegratorResult> out;
  const int total = static_cast<int>(std::size(kIntegrators) * std::size(kSteps));
  for (sim::Integrator in : kIntegrators) {
    for (double h : kSteps) {
      IntegratorResult r;
      r.integrator = in;
      r.step = h;
      drop_box(r);
      if (r.finite) slide_box(r);
      out.push_back(r);
      if (progress) progress(static_cast<int>(out.size()), total);
    }
  }
  // Pareto fronts of (cost, error) over the runs that stayed finite
  for (auto [y, front] :
       {std::pair{&IntegratorResult::penetration, &IntegratorResult::front_penetration},
        {&IntegratorResult::friction_error, &IntegratorResult::front_friction}}) {
    std::vector<ScatterPoint> pts;
    for (const IntegratorResult& r : out) {
      pts.push_back({r.finite ? r.us_per_second : -1, r.finite ? r.*y : -1, 0, false});
    }
    mark_pareto_front(pts);
    for (size_t k = 0; k < out.size(); ++k) out[k].*front = pts[k].front;
  }
  return out;
}

std::string write_integrator_report(const std::vector<IntegratorResult>& results,
                                    const std::string& dir) {
  std::filesystem::create_directories(dir);
  plot(results, &IntegratorResult::penetration, &IntegratorResult::front_penetration,
       "Deepest penetration of a dropped box against cost", "deepest penetration (m)",
       dir + "/simulation-penetration.svg");
  plot(results, &IntegratorResult::friction_error, &IntegratorResult::front_friction,
       "Friction error of a sliding box against cost", "relative stop-distance error",
       dir + "/simulation-friction.svg");
  const std::string page = dir + "/simulation-accuracy.md";
  std::ofstream o(page);
  o << "# Integrators and step sizes: what accuracy costs\n\n"
    << "Generated by `pindrag bench --report " << dir << "`. Each integrator of `sim::World` "
    << "(docs/simulation.md) runs the book's box tests (Yamane §6.4) at each step size, one "
    << "point per run, timed on this machine (CPU time of the steps only):\n\n"
    << "- **dropped box**: 1 kg, 0.2 × 0.1 × 0.3 m, dropped tilted from 0.5 m while moving "
       "sideways at 0.5 m/s, 3 s, friction (0.5, 0.4): the deepest penetration and the largest "
       "energy above the start (a box that gains energy has gone wrong);\n"
    << "- **sliding box**: the 1 kg cube at 1 m/s with (μS, μD) = (0.35, 0.25), "
       "(kFP, kFD) = (1000, 700): how far from Coulomb's 0.204 m it stops.\n\n"
    << "Contact: kP = 1e5, kD = 1e3, friction smoothing c = 0.1. Circled points are on the "
       "Pareto front (no other run is both cheaper and more accurate).\n\n"
    << "![penetration](simulation-penetration.svg)\n\n![friction](simulation-friction.svg)\n\n"
    << "| integrator | step (ms) | finite | deepest (mm) | energy gain (J) | friction error | "
       "µs per simulated s | front |\n|---|---|---|---|---|---|---|---|\n";
  for (const IntegratorResult& r : results) {
    o << "| " << sim::to_string(r.integrator) << " | " << cell(r.step * 1e3) << " | "
      << (r.finite ? "yes" : "no (blew up)") << " | "
      << (r.finite ? cell(r.penetration * 1e3) : "—") << " | "
      << (r.finite ? cell(r.energy_gain) : "—") << " | "
      << (r.finite ? cell(r.friction_error) : "—") << " | "
      << (r.finite ? cell(r.us_per_second) : "—") << " | "
      << (r.front_penetration ? "penetration " : "") << (r.front_friction ? "friction" : "")
      << " |\n";
  }
  return page;
}

}  // namespace cli
