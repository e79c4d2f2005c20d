// format_bvh (io/bvh_writer.hpp): a BvhDocument as text that parse_bvh reads back.
#include <charconv>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <vector>

#include "io/bvh_text.hpp"
#include "io/bvh_writer.hpp"

namespace io {

using namespace core;  // io reads and writes core's types

namespace {

using bvh_detail::num;

// writes v in fixed notation with 6 decimals; never "-0.000000"
char* put_fixed(char* out, double v) {
  const auto r = std::to_chars(out, out + 400, v, std::chars_format::fixed, 6);
  if (std::signbit(v) && v > -1e-6 && r.ptr - out == 9 &&
      std::memcmp(out, "-0.000000", 9) == 0) {  // also -0.0 itself
    std::memcpy(out, "0.000000", 8);
    return out + 8;
  }
  return r.ptr;
}

// shortest exact fixed form, padded to at least 7 significant digits
std::string frame_time_text(double t) {
  char buf[512];
  const auto r = std::to_chars(buf, buf + sizeof buf, t, std::chars_format::fixed);
  std::string s(buf, r.ptr);
  int significant = 0;
  bool started = false;
  for (char c : s) {
    if (c >= '1' && c <= '9') started = true;
    if (started && c >= '0' && c <= '9') ++significant;
  }
  if (significant < 7) {
    if (s.find('.') == std::string::npos) s += '.';
    s.append(static_cast<std::size_t>(7 - significant), '0');
  }
  return s;
}

// refuses what parse_bvh would refuse, or what cannot be written at all
void check_document(const BvhDocument& doc) {
  const std::size_t n = doc.nodes.size();
  if (n == 0 || doc.nodes[0].kind != BvhNode::Kind::kRoot) {
    throw std::invalid_argument("BVH writer: the document does not start with its ROOT");
  }
  if (doc.frames < 0 || doc.values.size() != static_cast<std::size_t>(doc.frames) * doc.channels) {
    throw std::invalid_argument("BVH writer: " + std::to_string(doc.values.size()) +
                                " values do not fill " + std::to_string(doc.frames) +
                                " frames of " + std::to_string(doc.channels) + " channels");
  }
  if (!std::isfinite(doc.frame_time) || doc.frame_time <= 0 || doc.frame_time > kMaxBvhFrameTime) {
    throw std::invalid_argument("BVH writer: frame time " + num(doc.frame_time) +
                                " is not in (0, kMaxBvhFrameTime]");
  }
  if (doc.frames > kMaxBvhFrames) {
    throw std::invalid_argument("BVH writer: " + std::to_string(doc.frames) +
                                " frames exceed kMaxBvhFrames");
  }
  const int joints = doc.joint_count();
  if (joints > kMaxBvhJoints || static_cast<int>(n) - joints > kMaxBvhJoints) {
    throw std::invalid_argument("BVH writer: more joints or End Sites than kMaxBvhJoints");
  }
  // every number within what the reader accepts
  auto check_value = [](double v, const std::string& where) {
    if (!std::isfinite(v) || std::abs(v) > kMaxBvhMagnitude) {
      throw std::invalid_argument("BVH writer: " + where + " = " + num(v) +
                                  " is not finite or exceeds kMaxBvhMagnitude");
    }
  };
  for (const BvhNode& node : doc.nodes) {
    for (int c = 0; c < 3; ++c) check_value(node.offset[c], "an OFFSET");
    if (node.name.size() > 4096) {
      throw std::invalid_argument("BVH writer: a joint name is longer than 4096 bytes");
    }
  }
  for (std::size_t k = 0; k < doc.values.size(); ++k) {
    if (!(std::abs(doc.values[k]) <= kMaxBvhMagnitude)) {
      check_value(doc.values[k], "value " + std::to_string(k % std::max(1, doc.channels) + 1) +
                                     " of frame " +
                                     std::to_string(k / std::max(1, doc.channels) + 1));
    }
  }
}

// joint names as written: sanitized and unique (empty for End Sites)
std::vector<std::string> written_names(const BvhDocument& doc) {
  std::vector<std::string> names(doc.nodes.size());
  std::unordered_set<std::string> used;
  for (std::size_t k = 0; k < doc.nodes.size(); ++k) {
    if (doc.nodes[k].is_end_site()) continue;
    const std::string base = sanitize_bvh_name(doc.nodes[k].name);
    std::string name = base;
    for (int i = 2; used.count(name); ++i) name = base + "_" + std::to_string(i);
    used.insert(name);
    names[k] = name;
  }
  return names;
}

// HIERARCHY up to the last '}', checking that the nodes are a depth-first order with one ROOT
// and consecutive channels
void append_hierarchy(const BvhDocument& doc,
                      const std::vector<std::string>& names,
                      std::string& out) {
  char buf[512];
  out += "HIERARCHY\n";
  std::vector<int> open;  // stack of open nodes
  int channels = 0;
  for (std::size_t k = 0; k < doc.nodes.size(); ++k) {
    const BvhNode& node = doc.nodes[k];
    if (k > 0 && node.kind == BvhNode::Kind::kRoot) {
      throw std::invalid_argument("BVH writer: more than one ROOT");
    }
    while (!open.empty() && open.back() != node.parent) {
      open.pop_back();
      out.append(open.size(), '\t');
      out += "}\n";
    }
    if (open.empty() && k > 0) {
      throw std::invalid_argument("BVH writer: nodes are not in depth-first order");
    }
    if (node.first_value != channels || (node.is_end_site() && !node.channels.empty())) {
      throw std::invalid_argument("BVH writer: the channel layout of node " + std::to_string(k) +
                                  " is inconsistent");
    }
    channels += static_cast<int>(node.channels.size());
    const std::string indent(open.size(), '\t');
    out += indent;
    if (node.kind == BvhNode::Kind::kRoot)
      out += "ROOT " + names[k] + "\n";
    else if (node.kind == BvhNode::Kind::kJoint)
      out += "JOINT " + names[k] + "\n";
    else
      out += "End Site\n";
    out += indent + "{\n";
    out += indent + "\tOFFSET ";
    for (int c = 0; c < 3; ++c) {
      if (c) out += ' ';
      out.append(buf, put_fixed(buf, node.offset[c]));
    }
    out += '\n';
    if (!node.is_end_site()) {
      out += indent + "\tCHANNELS " + std::to_string(node.channels.size());
      for (BvhChannel c : node.channels) {
        out += ' ';
        out += to_string(c);
      }
      out += '\n';
    }
    open.push_back(static_cast<int>(k));
  }
  while (!open.empty()) {
    open.pop_back();
    out.append(open.size(), '\t');
    out += "}\n";
  }
  if (channels != doc.channels) {
    throw std::invalid_argument("BVH writer: the nodes hold " + std::to_string(channels) +
                                " channels, the document says " + std::to_string(doc.channels));
  }
}

// MOTION, Frames, Frame Time and one line of values per frame
void append_motion(const BvhDocument& doc, std::string& out) {
  char buf[512];
  out += "MOTION\nFrames: " + std::to_string(doc.frames) + "\n";
  out += "Frame Time: " + frame_time_text(doc.frame_time) + "\n";
  for (int f = 0; f < doc.frames; ++f) {
    const double* v = doc.frame(f);
    for (int c = 0; c < doc.channels; ++c) {
      if (c) out += ' ';
      out.append(buf, put_fixed(buf, v[c]));
    }
    out += '\n';
  }
}

}  // namespace

std::string format_bvh(const BvhDocument& doc) {
  check_document(doc);
  const std::vector<std::string> names = written_names(doc);
  std::string out;
  out.reserve(doc.nodes.size() * 96 + doc.values.size() * 12 + 64);
  append_hierarchy(doc, names, out);
  append_motion(doc, out);
  return out;
}

}  // namespace io
