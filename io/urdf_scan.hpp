// The URDF loader's tinyxml2 pass over <robot> (internal to io/urdf*.cpp): what urdfdom drops
// or cannot read. It names ignored elements in warnings, renames Bullet's <capsule> to <cylinder>
// so urdfdom reads its radius and length, removes shapes urdfdom cannot read, and checks before
// urdfdom runs what urdfdom gets wrong: the link count, repeated joint names (with the lines of
// every definition) and the tree (urdfdom keeps only the last of several parent joints, and leaks
// a rootless cycle).
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

namespace tinyxml2 {
class XMLElement;
}

namespace io::urdf_internal {

enum class ShapeKind { kStandard, kCapsule };

struct LinkScan {
  std::vector<ShapeKind> visual;     // one per <visual> left for urdfdom, in document order
  std::vector<ShapeKind> collision;  // one per <collision> left for urdfdom
};

struct JointScan {
  std::string name, parent, child;  // parent and child link names
  int line = 0;
};

struct Scan {
  std::vector<std::string> link_order;  // link names in document order
  std::unordered_map<std::string, LinkScan> links;
  std::vector<JointScan> joints;      // in document order
  std::vector<std::string> warnings;  // without the source prefix
  std::vector<std::string> errors;    // without the source prefix; any one refuses the file
};

/// Scans the children of <robot>, changing the document as described above.
Scan scan_document(tinyxml2::XMLElement* robot);

}  // namespace io::urdf_internal
