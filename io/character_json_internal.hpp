// Internals of the character JSON format shared by its source files (not part of the API):
//   character_json_read.cpp       text to Model: header, links, build, restoring exact bits
//   character_json_links.cpp      one link object to a LinkSpec (joint, inertial, shapes, range)
//   character_json_structure.cpp  tree rules with pointers; builder messages to pointers
//   character_json_write.cpp      Model to text: an ordered tree and its printer
//   character_json_inertia.cpp    COM and inertia that reproduce a spatial inertia bit for bit
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/model.hpp"
#include "core/model_builder.hpp"
#include "io/character_json.hpp"
#include "io/json_reader.hpp"

namespace io::character_json {

// at most this many errors and warnings are reported; the rest are counted
constexpr std::size_t kMaxReported = 100;
// a range needs no more vertices than its triangles have corners
constexpr std::size_t kMaxRangeVertices = 3 * static_cast<std::size_t>(core::kMaxRangeTriangles);
// range triangles over all joints of a file (the builder's range preprocessing grows with the
// square of a range's triangles, so a file of many maximal ranges would take minutes)
constexpr std::size_t kMaxRangeTrianglesPerFile = 32768;
// axes within this distance of unit length (squared norm) are kept bit for bit
constexpr double kUnitTolerance = 1e-14;

inline bool one_dof(core::JointType t) {
  return t == core::JointType::kRevolute || t == core::JointType::kPrismatic;
}

/// A reader that collects every error of a file, and counts range triangles over all joints.
class CharacterReader : public JsonReader {
 public:
  CharacterReader() : JsonReader(JsonStyle{}, OnError::kCollect) {}
  std::size_t range_triangles = 0;  // read so far, over all joints
};

/// What the file said about a link beyond its LinkSpec: pointers for messages and the values the
/// builder would renormalize, which are restored bit for bit after building.
struct LinkInfo {
  std::string ptr;  // /links/k
  bool has_joint_name = false;
  std::optional<core::Vector3> axis;
  std::optional<core::Quaternion> range_frame;
  std::optional<core::Quaternion> standard_orientation;
};

/// Reads link object `j` into `l` and `info`; meshes are looked for in `base_dir` (may be empty).
void read_link(CharacterReader& rd,
               const JsonField& j,
               core::LinkSpec& l,
               LinkInfo& info,
               const std::string& base_dir);

/// Tree rules with pointers: unique link and joint names, parents that exist, one root, no cycles.
void check_structure(CharacterReader& rd,
                     const std::vector<core::LinkSpec>& links,
                     const std::vector<LinkInfo>& info);

/// The pointer of the field a builder violation ("link 'x': ...", "joint 'y': ...") is about;
/// the link is looked up by name, the field by the words of the message.
std::string locate_violation(const std::string& violation,
                             const std::unordered_map<std::string, std::size_t>& by_name,
                             const std::unordered_map<std::string, std::size_t>& by_joint,
                             const std::vector<LinkInfo>& info);

/// A centre of mass and an inertia about it, as written to a file.
struct InertiaForm {
  core::Vector3 com = core::Vector3::Zero();
  core::Matrix3 I = core::Matrix3::Zero();
};

/// COM c and inertia about it I_c such that SpatialInertia::from_com(m, c, I_c) reproduces `S`
/// bit for bit and the builder accepts I_c (see character_json_inertia.cpp).
InertiaForm inertia_form(const core::SpatialInertia& S);

}  // namespace io::character_json
