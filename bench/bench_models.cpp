#include "bench/bench_models.hpp"

#include <urdf_parser/urdf_parser.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <kdl_parser/kdl_parser.hpp>

#include "core/human_figure.hpp"
#include "io/urdf.hpp"

namespace bench {

std::string bench_models_dir() {
  namespace fs = std::filesystem;
#ifdef PINDRAG_BENCH_MODELS_DIR
  std::string dir = PINDRAG_BENCH_MODELS_DIR;
#else
  std::string dir;
#endif
  if (const char* e = std::getenv("PINDRAG_BENCH_MODELS_DIR"); e && *e) dir = e;
  return !dir.empty() && fs::is_directory(dir) ? dir : std::string();
}

const std::vector<BenchModel>& models() {
  static const std::vector<BenchModel> all = [] {
    std::vector<BenchModel> out;
    out.push_back({"human48", core::build_human_figure({}), "", ""});
    const std::string dir = bench_models_dir();
    if (dir.empty()) {
      std::cerr
          << "benchmark model folder not found (set PINDRAG_BENCH_MODELS_DIR): only human48\n";
      return out;
    }
    auto file = [&](const std::string& f) {
      return std::filesystem::exists(dir + "/" + f) ? dir + "/" + f : std::string();
    };
    io::LoadOptions free_root;
    free_root.root = io::RootJoint::kFree;
    for (const char* h : {"human48", "human34"}) {
      const std::string urdf = file(std::string(h) + ".urdf");
      if (urdf.empty()) continue;
      out.push_back({std::string(h) + "_urdf", io::load_urdf_file(urdf, free_root).model,
                     file(std::string(h) + "_free.xml"), file(std::string(h) + "_float6.urdf")});
    }
    for (int n : {8, 32, 64, 128, 512}) {
      const std::string base = "chain" + std::to_string(n);
      const std::string urdf = file(base + ".urdf");
      if (urdf.empty()) continue;
      out.push_back({base, io::load_urdf_file(urdf).model, file(base + ".xml"), urdf});
    }
    return out;
  }();
  return all;
}

MujocoModel::MujocoModel(const std::string& path) {
  char error[1000] = "";
  m = mj_loadXML(path.c_str(), nullptr, error, sizeof error);
  if (!m) {
    std::cerr << "MuJoCo could not load " << path << ": " << error << "\n";
    return;
  }
  d = mj_makeData(m);
}

MujocoModel::~MujocoModel() {
  if (d) mj_deleteData(d);
  if (m) mj_deleteModel(m);
}

bool load_kdl_tree(const std::string& urdf_path, KDL::Tree& tree) {
  const auto urdf = urdf::parseURDFFile(urdf_path);
  return urdf && kdl_parser::treeFromUrdfModel(*urdf, tree);
}

}  // namespace bench
