// The models every benchmark runs on, loaded once: our human figure, the shared benchmark URDFs
// (../shared/bench) and their MuJoCo and KDL twins, so peers compare on identical input.
#pragma once

#include <mujoco/mujoco.h>

#include <kdl/tree.hpp>
#include <memory>
#include <string>
#include <vector>

#include "core/model.hpp"

namespace bench {

struct BenchModel {
  std::string name;  // benchmark argument name, e.g. "human48_urdf"
  std::shared_ptr<const core::Model> model;
  std::string mujoco_xml;  // MJCF twin, empty when there is none
  std::string kdl_urdf;    // URDF for KDL (float6 base for free-root figures)
};

/// human48 (ours), human48_urdf, human34_urdf and chainN (N = 8, 32, 64, 128, 512), as far as
/// the shared benchmark folder is present (bench_models_dir(); absent models are skipped).
const std::vector<BenchModel>& models();

/// ../shared/bench, or $PINDRAG_BENCH_MODELS_DIR; empty when absent.
std::string bench_models_dir();

/// RAII MuJoCo model + data; null when the file does not load (the error is printed).
struct MujocoModel {
  explicit MujocoModel(const std::string& path);
  ~MujocoModel();
  MujocoModel(const MujocoModel&) = delete;
  MujocoModel& operator=(const MujocoModel&) = delete;
  mjModel* m = nullptr;
  mjData* d = nullptr;
};

/// KDL tree from a URDF (via urdfdom, never kdl_parser::treeFromFile); false on failure.
bool load_kdl_tree(const std::string& urdf_path, KDL::Tree& tree);

}  // namespace bench
