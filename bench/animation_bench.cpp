// Animation file formats and editing in motion on the shared motion-capture files (../shared/data,
// or $PINDRAG_DATA_DIR; the benchmarks are left out when it is absent).
// Names: BM_BvhParse/<file>, BM_BvhWrite/<file> (bytes_per_second), BM_GltfExport/<frames>,
// BM_EditInMotion/<clip> (items_per_second = clip frames edited per second).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "animator/edit_layer.hpp"
#include "animator/motion_editor.hpp"
#include "core/kinematics.hpp"
#include "io/bvh.hpp"
#include "io/gltf.hpp"

namespace {

namespace fs = std::filesystem;

std::string data_dir() {
  const char* env = std::getenv("PINDRAG_DATA_DIR");
  const std::string dir = env != nullptr && *env != '\0' ? env : PINDRAG_DATA_DIR;
  return fs::is_directory(dir + "/bvh") ? dir : "";
}

std::string read_text(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

void bvh_parse(benchmark::State& state, const std::string& path) {
  const std::string text = read_text(path);
  for (auto _ : state) {
    io::BvhDocument doc = io::parse_bvh(text, path);
    benchmark::DoNotOptimize(doc.values.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) *
                          static_cast<int64_t>(text.size()));
}

// the whole export of an imported clip: rotations to Euler angles (unwrapped) and the text
void bvh_write(benchmark::State& state, const std::string& path) {
  const io::BvhImport imp = io::load_bvh_file(path);
  io::BvhExportOptions o;
  o.layout = &imp.layout;
  std::size_t bytes = 0;
  for (auto _ : state) {
    const std::string text = io::write_bvh(*imp.model, imp.clip, o);
    bytes = text.size();
    benchmark::DoNotOptimize(text.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(bytes));
}

// a GLB in memory of the CMU walk's skeleton with `frames` frames (the walk repeated)
void gltf_export(benchmark::State& state, const std::string& path) {
  const io::BvhImport imp = io::load_bvh_file(path);
  core::Clip clip;
  clip.frame_time = imp.clip.frame_time;
  const auto frames = static_cast<std::size_t>(state.range(0));
  for (std::size_t k = 0; k < frames; ++k)
    clip.frames.push_back(imp.clip.frames[k % imp.clip.frames.size()]);
  io::GltfExportOptions o;
  o.stick_figure = true;
  std::size_t bytes = 0;
  for (auto _ : state) {
    const auto glb = io::write_glb(*imp.model, &clip, nullptr, o);
    bytes = glb.size();
    benchmark::DoNotOptimize(glb.data());
  }
  state.counters["glb_MB"] = static_cast<double>(bytes) / 1e6;
}

// the links of one clip's skeleton that the edit pins and drags (the files name them differently)
struct EditLinks {
  std::array<const char*, 4> pinned;  // both feet, the left hand, the head
  const char* dragged;                // the right hand
};

// every frame of the clip edited in motion: four moving pins (the feet, the left hand and the head
// follow the clip) while the right hand is dragged 12 cm off its path
void edit_in_motion(benchmark::State& state, const std::string& path, const EditLinks& links) {
  const io::BvhImport imp = io::load_bvh_file(path);
  const core::Model& m = *imp.model;
  const core::Clip& clip = imp.clip;
  std::vector<animator::Pin> pins;
  for (const char* link : links.pinned) {
    pins.push_back(animator::Pin{.link = m.link_index(link), .mode = ik::TaskMode::kPose});
    if (pins.back().link <= 0) {
      state.SkipWithError((std::string("no link ") + link).c_str());
      return;
    }
  }
  const int hand = m.link_index(links.dragged);
  if (hand <= 0) {
    state.SkipWithError((std::string("no link ") + links.dragged).c_str());
    return;
  }
  // the drag targets, frame by frame: the clip's hand raised and moved forward
  std::vector<core::Vector3> targets(clip.frames.size());
  core::Data d(m);
  for (int f = 0; f < clip.size(); ++f) {
    core::forward_kinematics(m, d, clip.frames[f]);
    targets[f] = d.X_W[hand].p + core::Vector3(0, 0.08, 0.09);
  }
  const animator::LayerStack no_layers;
  animator::MotionEditor editor(m, animator::motion_edit_settings(clip.frame_time));
  for (auto _ : state) {
    editor.begin(clip, no_layers, 0);
    for (int f = 1; f < clip.size(); ++f) {
      const ik::LinkTask drag{.role = ik::kDrag, .link = hand, .target_W = targets[f]};
      benchmark::DoNotOptimize(editor.edit(clip, no_layers, f, pins, drag).data());
    }
    state.PauseTiming();
    if (editor.report().status != ik::Report::Status::kOk) {
      state.SkipWithError(editor.report().message.c_str());
      break;
    }
    benchmark::DoNotOptimize(editor.finish("bench", 0.1));
    state.ResumeTiming();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * (clip.size() - 1));
}

const bool registered = [] {
  const std::string dir = data_dir();
  if (dir.empty()) return false;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir + "/bvh")) {
    if (e.path().extension() == ".bvh") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& p : files) {
    const std::string n = "/" + p.stem().string();
    benchmark::RegisterBenchmark(("BM_BvhParse" + n).c_str(), bvh_parse, p.string())
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_BvhWrite" + n).c_str(), bvh_write, p.string())
        ->Unit(benchmark::kMillisecond);
  }
  const std::string walk = dir + "/bvh/cmu_walk_cgspeed.bvh";
  benchmark::RegisterBenchmark("BM_GltfExport", gltf_export, walk)
      ->Arg(10000)
      ->Unit(benchmark::kMillisecond);
  // the 31-joint CMU skeletons, as cgspeed and the 3ds Max release name their joints
  const std::vector<std::pair<std::string, EditLinks>> clips = {
      {"cmu_walk_cgspeed", {{"LeftFoot", "RightFoot", "LeftHand", "Head"}, "RightHand"}},
      {"cmu_131_01_mj_walk_3dsmax", {{"LeftAnkle", "RightAnkle", "lhand", "Head"}, "rhand"}}};
  for (const auto& [clip, links] : clips) {
    benchmark::RegisterBenchmark(("BM_EditInMotion/" + clip).c_str(), edit_in_motion,
                                 dir + "/bvh/" + clip + ".bvh", links)
        ->Unit(benchmark::kMillisecond);
  }
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
