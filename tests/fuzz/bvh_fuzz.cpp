// libFuzzer harness for io/bvh.hpp. Any input must parse or fail with core::ModelError;
// nothing else may escape, crash, hang or leak. A document that parses must import; its export
// (names, channel orders and units of the file) must parse again with the same hierarchy and frame
// count, and every joint and End Site must land where the original put it, within what the
// writer's 6 decimals allow plus, for a joint whose position channels import as a constant
// translation (io/bvh_import.hpp), the deviation from that constant the import declares it drops.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/bvh.hpp"

namespace {

using io::BvhDocument;

// an upper bound on the position error the writer's rounding can cause for a frame: 6 decimals
// of a degree (< 1e-8 rad per angle) on every lever, 5e-7 units per coordinate, per level
double tolerance(const BvhDocument& d, int frame) {
  double levers = 1;
  int depth = 1;
  for (const io::BvhNode& n : d.nodes) {
    levers += n.offset.norm();
    int k = 1;
    for (int p = n.parent; p >= 0; p = d.nodes[p].parent) ++k;
    depth = std::max(depth, k);
  }
  if (frame >= 0 && d.channels > 0) {
    for (int c = 0; c < d.channels; ++c) levers += std::abs(d.frame(frame)[c]);
  }
  return depth * (1e-7 * levers + 1e-6);
}

// Per node, the distance (file units) the import may move it from where the file puts it: each
// joint imported at a constant translation on its chain (itself included) may be off by
// kBvhConstantTranslationTolerance of the figure's size in each component (√3 of it in length),
// and rotations above it carry that offset without growing it.
std::vector<double> conversion_allowance(const BvhDocument& d, const io::BvhImport& imp) {
  // the figure's size as the import takes it: 1 m for a skeleton under 1 µm
  const double extent = io::bvh_rest_extent(d).largest * imp.layout.scale;
  const double figure_metres = extent > 1e-6 ? extent : 1.0;
  const double per_joint =
      std::sqrt(3.0) * io::kBvhConstantTranslationTolerance * figure_metres / imp.layout.scale;
  std::vector<double> allowance(d.nodes.size(), 0.0);
  for (std::size_t k = 0; k < d.nodes.size(); ++k) {
    const int parent = d.nodes[k].parent;
    allowance[k] = parent >= 0 ? allowance[parent] : 0.0;  // parents come first in file order
    const int link = imp.node_link[k];
    if (link > 0 &&
        std::find(imp.constant_translation_joints.begin(), imp.constant_translation_joints.end(),
                  imp.model->link_name[link]) != imp.constant_translation_joints.end()) {
      allowance[k] += per_joint;
    }
  }
  return allowance;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  BvhDocument doc;
  try {
    doc = io::parse_bvh(text, "fuzz.bvh");
  } catch (const core::ModelError&) {
    return 0;
  }
  if (doc.values.size() != static_cast<std::size_t>(doc.frames) * doc.channels) std::abort();

  // a parsed document always imports
  const io::BvhImport imp = io::import_bvh(doc, "fuzz.bvh");
  io::BvhExportOptions options;
  options.layout = &imp.layout;
  std::string written;
  try {
    written = io::write_bvh(*imp.model, imp.clip, options);
  } catch (const std::invalid_argument&) {
    // only a value at the edge of kMaxBvhMagnitude may refuse to be written
    double largest = 0;
    for (double v : doc.values) largest = std::max(largest, std::abs(v));
    for (const auto& n : doc.nodes) largest = std::max(largest, n.offset.cwiseAbs().maxCoeff());
    if (largest < 0.25 * io::kMaxBvhMagnitude) std::abort();
    return 0;
  }
  const BvhDocument again = io::parse_bvh(written, "fuzz-rewritten.bvh");
  if (again.frames != doc.frames || again.nodes.size() != doc.nodes.size()) std::abort();
  for (std::size_t k = 0; k < doc.nodes.size(); ++k) {
    if (again.nodes[k].kind != doc.nodes[k].kind || again.nodes[k].parent != doc.nodes[k].parent) {
      std::abort();
    }
  }
  if (std::abs(again.frame_time - doc.frame_time) > 1e-12 * doc.frame_time) std::abort();
  // (rest poses may differ by design: position channels are written over OFFSET 0 0 0)
  const std::vector<double> allowance = conversion_allowance(doc, imp);
  for (int f = 0; f < std::min(doc.frames, 8); ++f) {
    const auto a = io::bvh_world_poses(doc, f);
    const auto b = io::bvh_world_poses(again, f);
    const double tol = tolerance(doc, f);
    for (std::size_t k = 0; k < a.size(); ++k) {
      if (!((a[k].p - b[k].p).norm() <= tol + allowance[k])) std::abort();
    }
  }
  return 0;
}
