#include "io/bvh_writer.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/data.hpp"
#include "core/kinematics.hpp"
#include "io/atomic_file.hpp"
#include "io/bvh_euler.hpp"
#include "io/bvh_import.hpp"
#include "io/bvh_text.hpp"

namespace io {

using namespace core;  // io reads and writes core's types

namespace {

using bvh_detail::kDegree;
using bvh_detail::num;

// how one written node takes its values from the model
struct Written {
  int link = -1;  // model link (-1 for an added End Site)
  Transform pre;  // constant transform from the written parent to the joint's parent
  BvhRotationOrder order{};
  bool position = false;  // writes position channels
};

// the rotation order of a layout joint: its rotation channels, missing axes appended X, Y, Z
BvhRotationOrder order_of(const std::vector<BvhChannel>& channels) {
  BvhRotationOrder order{};
  int n = 0;
  bool used[3] = {false, false, false};
  for (BvhChannel c : channels) {
    if (is_rotation(c) && !used[channel_axis(c)] && n < 3) {
      used[channel_axis(c)] = true;
      order[n++] = channel_axis(c);
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (!used[a]) order[n++] = a;
  }
  return order;
}

// The written nodes, in the model's depth-first order (a valid BVH pre-order), and how each takes
// its values. Fixed links fold into their written parent, or become End Sites when nothing moves
// below them. `s` is metres per file unit.
void write_nodes(const Model& model,
                 const BvhExportOptions& options,
                 const std::optional<BvhRotationOrder>& forced,
                 double s,
                 BvhDocument& doc,
                 std::vector<Written>& written) {
  const BvhRotationOrder zxy{2, 0, 1};
  const int nj = model.njoints;
  // which links move something below them
  std::vector<char> moving(nj, 0);
  for (int i = nj - 1; i >= 1; --i) {
    if (model.joint_type[i] != JointType::kFixed) moving[i] = 1;
    if (model.parent[i] > 0 && moving[i]) moving[model.parent[i]] = 1;
  }
  std::vector<int> anchor(nj, -1);                      // written node a link hangs from
  std::vector<Transform> C(nj, Transform::Identity());  // that node's frame → the link frame
  for (int i = 1; i < nj; ++i) {
    const int p = model.parent[i];
    BvhNode node;
    Written w;
    w.link = i;
    const bool root = p == 0;
    const int a = root ? -1 : anchor[p];
    const Transform Cp = root ? Transform::Identity() : C[p];
    if (!root && model.joint_type[i] == JointType::kFixed) {
      const Transform T = Cp * model.X_PJ[i];
      const bool leaf = model.subtree_end[i] == i + 1;
      if (moving[i] || !leaf) {  // fold into the written parent
        anchor[i] = a;
        C[i] = T;
        continue;
      }
      node.kind = BvhNode::Kind::kEndSite;
      node.parent = a;
      node.offset = T.p / s;
    } else {
      const JointType t = model.joint_type[i];
      const BvhLayout::Joint* lj =
          options.layout ? options.layout->find(model.link_name[i]) : nullptr;
      w.order = forced ? *forced : lj ? order_of(lj->channels) : zxy;
      w.position = root || t == JointType::kFree || t == JointType::kPrismatic;
      w.pre = Cp;
      node.kind = root ? BvhNode::Kind::kRoot : BvhNode::Kind::kJoint;
      node.name = model.link_name[i];
      node.parent = a;
      // a joint that only rotates keeps its origin: the constant OFFSET; one that translates
      // carries its whole translation in position channels over OFFSET 0 0 0
      node.offset = w.position ? Vector3::Zero() : Vector3((Cp * model.X_PJ[i]).p / s);
      if (w.position) {
        node.channels = {BvhChannel::kXposition, BvhChannel::kYposition, BvhChannel::kZposition};
      }
      for (int axis : w.order) {
        node.channels.push_back(
            static_cast<BvhChannel>(static_cast<int>(BvhChannel::kXrotation) + axis));
      }
      anchor[i] = static_cast<int>(doc.nodes.size());
      C[i] = Transform::Identity();
    }
    doc.nodes.push_back(std::move(node));
    written.push_back(w);
  }
}

// a leaf joint gets an End Site at its origin, unless it comes from an imported file as it is
void add_end_sites(const BvhLayout* layout, BvhDocument& doc, std::vector<Written>& written) {
  std::vector<int> nchildren(doc.nodes.size(), 0);
  for (const BvhNode& node : doc.nodes) {
    if (node.parent >= 0) ++nchildren[node.parent];
  }
  std::vector<BvhNode> nodes;
  std::vector<Written> ws;
  std::vector<int> remap(doc.nodes.size(), -1);
  for (std::size_t k = 0; k < doc.nodes.size(); ++k) {
    BvhNode node = std::move(doc.nodes[k]);
    if (node.parent >= 0) node.parent = remap[node.parent];
    remap[k] = static_cast<int>(nodes.size());
    const bool add_end =
        !node.is_end_site() && nchildren[k] == 0 && !(layout && layout->find(node.name));
    nodes.push_back(std::move(node));
    ws.push_back(written[k]);
    if (add_end) {
      BvhNode e;
      e.kind = BvhNode::Kind::kEndSite;
      e.parent = remap[k];
      nodes.push_back(std::move(e));
      ws.push_back(Written{});
    }
  }
  doc.nodes = std::move(nodes);
  written = std::move(ws);
}

// values: each joint's pose relative to its written parent, as Euler angles unwrapped across
// frames
void write_values(const Model& model,
                  const Clip& clip,
                  const std::vector<Written>& written,
                  double s,
                  const std::function<void(double)>& progress,
                  BvhDocument& doc) {
  doc.frames = clip.size();
  doc.frame_time = clip.frame_time;
  doc.values.resize(static_cast<std::size_t>(doc.frames) * doc.channels);
  Data data(model);
  std::vector<Vector3> previous(doc.nodes.size(), Vector3::Zero());
  const int step = std::max(1, doc.frames / 50);
  for (int f = 0; f < doc.frames; ++f) {
    forward_kinematics(model, data, clip.frames[f]);
    double* row = doc.values.data() + static_cast<std::size_t>(f) * doc.channels;
    for (std::size_t k = 0; k < doc.nodes.size(); ++k) {
      const BvhNode& node = doc.nodes[k];
      if (node.is_end_site()) continue;
      const Written& w = written[k];
      const Transform X = w.pre * data.X_P[w.link];
      double* v = row + node.first_value;
      if (w.position) {
        for (int c = 0; c < 3; ++c) *v++ = X.p[c] / s;
      }
      const Vector3 angles = matrix_to_euler(X.R, w.order, f > 0 ? &previous[k] : nullptr);
      previous[k] = angles;
      for (int c = 0; c < 3; ++c) *v++ = angles[c] / kDegree;
    }
    if (progress && f % step == 0) progress(static_cast<double>(f) / doc.frames);
  }
  if (progress) progress(1.0);
}

}  // namespace

std::string sanitize_bvh_name(std::string_view name) {
  std::string s(name);
  for (char& c : s) {
    const bool ok =
        (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) c = '_';
  }
  return s.empty() ? "joint" : s;
}

std::optional<double> parse_bvh_units(std::string_view value, std::string_view option) {
  using bvh_detail::iequals;
  if (iequals(value, "m")) return 1.0;
  if (iequals(value, "cm")) return 0.01;
  if (iequals(value, "source")) return std::nullopt;
  throw std::invalid_argument(std::string(option) + ": '" + std::string(value) +
                              "' (rule: one of m, cm, source)");
}

std::optional<std::string> parse_bvh_order(std::string_view value, std::string_view option) {
  if (bvh_detail::iequals(value, "source")) return std::nullopt;
  if (const auto order = parse_rotation_order(value)) return to_string(*order);
  throw std::invalid_argument(std::string(option) + ": '" + std::string(value) +
                              "' (rule: one of XYZ, XZY, YXZ, YZX, ZXY, ZYX, source)");
}

BvhDocument make_bvh_document(const Model& model,
                              const Clip& clip,
                              const BvhExportOptions& options) {
  if (model.njoints < 2) throw std::invalid_argument("BVH export: the model has no links");
  if (const std::string e = check_clip(model, clip); !e.empty()) {
    throw std::invalid_argument("BVH export: the clip does not fit model '" + model.name +
                                "': " + e);
  }
  std::optional<BvhRotationOrder> forced;
  if (options.rotation_order) {
    forced = parse_rotation_order(*options.rotation_order);
    if (!forced) {
      throw std::invalid_argument("BVH export: rotation order '" + *options.rotation_order +
                                  "' is not a permutation of XYZ");
    }
  }
  const double s = options.scale ? *options.scale : options.layout ? options.layout->scale : 1.0;
  if (!std::isfinite(s) || s <= 0) {
    throw std::invalid_argument("BVH export: scale " + num(s) +
                                " is not a positive finite number (metres per file unit)");
  }
  BvhDocument doc;
  std::vector<Written> written;
  write_nodes(model, options, forced, s, doc, written);
  add_end_sites(options.layout, doc, written);
  for (BvhNode& node : doc.nodes) {
    node.first_value = doc.channels;
    doc.channels += static_cast<int>(node.channels.size());
  }
  write_values(model, clip, written, s, options.progress, doc);
  return doc;
}

std::string write_bvh(const Model& model, const Clip& clip, const BvhExportOptions& options) {
  return format_bvh(make_bvh_document(model, clip, options));
}

void save_bvh_file(const Model& model,
                   const Clip& clip,
                   const std::string& path,
                   const BvhExportOptions& options) {
  write_file_atomically(path, write_bvh(model, clip, options));
}

}  // namespace io
