// `pindrag simulate --scene SCENE.json`: the scene file (docs/simulation.md) read into a
// sim::World, and the run that records it. Every refusal names the field as a JSON pointer.
#pragma once

#include <memory>
#include <nlohmann/json.hpp>

#include "io/json_reader.hpp"
#include "sim/scene.hpp"
#include "sim/world.hpp"

namespace cli {

struct SimulationRun {
  std::unique_ptr<sim::World> world;
  double duration = 1.0;  // simulated seconds
  int record_every = 10;  // steps between recorded frames
};

/// The scene of an "effects" array of sim::Effect names (absent: no effect); an unknown name
/// fails naming its element. Shared by scene files and `pindrag solve` requests.
sim::Scene read_effects(io::JsonFields& f, const io::JsonField& effects);

/// @throws RequestError naming the field and the rule
SimulationRun read_simulation_scene(const nlohmann::json& scene);

/// Steps the world for the run's duration, recording every record_every-th step: frames (time,
/// bodies' root poses and velocities, contact forces, energy), stage call counts and the median
/// wall time of one step (µs).
nlohmann::json run_simulation(SimulationRun& run);

}  // namespace cli
