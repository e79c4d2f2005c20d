#include "io/urdf_scan.hpp"

#include <tinyxml2.h>

#include <algorithm>
#include <map>

#include "core/model_builder.hpp"

namespace io::urdf_internal {

namespace {

std::string attr(const tinyxml2::XMLElement* e, const char* name) {
  const char* v = e->Attribute(name);
  return v ? std::string(v) : std::string();
}

std::string line_of(const tinyxml2::XMLElement* e) {
  return "line " + std::to_string(e->GetLineNum());
}

struct TagCount {
  int count = 0;
  int first_line = 0;
};

void count_tag(std::map<std::string, TagCount>& tags, const tinyxml2::XMLElement* e) {
  TagCount& t = tags[e->Name()];
  if (t.count++ == 0) t.first_line = e->GetLineNum();
}

// <visual> or <collision>: renames Bullet's <capsule> to <cylinder> for urdfdom (same radius and
// length attributes) and remembers it; returns false when the element must be removed
bool scan_shape(tinyxml2::XMLElement* shape,
                const std::string& link,
                const char* kind,
                std::vector<ShapeKind>& out,
                int& materials,
                Scan& scan) {
  const std::string where = "link '" + link + "': " + kind + " (" + line_of(shape) + ")";
  int geometries = 0;
  for (tinyxml2::XMLElement* c = shape->FirstChildElement(); c; c = c->NextSiblingElement()) {
    const std::string tag = c->Name();
    if (tag == "geometry") {
      if (++geometries > 1) {
        scan.warnings.push_back(where + ": only the first <geometry> is used; the <geometry> at " +
                                line_of(c) + " is ignored");
      }
    } else if (tag == "material" && std::string(kind) == "visual") {
      ++materials;
    } else if (tag != "origin") {
      scan.warnings.push_back(where + ": <" + tag + "> (" + line_of(c) +
                              ") is not supported and is ignored");
    }
  }
  tinyxml2::XMLElement* geometry = shape->FirstChildElement("geometry");
  tinyxml2::XMLElement* g = geometry ? geometry->FirstChildElement() : nullptr;
  if (!g) {
    out.push_back(ShapeKind::kStandard);  // urdfdom reports the missing geometry
    return true;
  }
  for (const tinyxml2::XMLElement* extra = g->NextSiblingElement(); extra;
       extra = extra->NextSiblingElement()) {
    scan.warnings.push_back(where + ": only the first shape in <geometry> is used; <" +
                            std::string(extra->Name()) + "> (" + line_of(extra) + ") is ignored");
  }
  const std::string type = g->Name();
  if (type == "box" || type == "sphere" || type == "cylinder" || type == "mesh") {
    out.push_back(ShapeKind::kStandard);
    return true;
  }
  if (type == "capsule") {
    if (!g->Attribute("radius") || !g->Attribute("length")) {
      scan.errors.push_back(where +
                            ": <capsule> needs radius and length attributes (rule: "
                            "Bullet's capsule is <capsule radius=\"r\" length=\"l\"/>)");
      return false;
    }
    scan.warnings.push_back(where + ": <capsule radius=\"" + attr(g, "radius") + "\" length=\"" +
                            attr(g, "length") +
                            "\"> is a non-standard Bullet extension; read as a capsule along its "
                            "z axis, length between the sphere centres");
    g->SetName("cylinder");  // urdfdom then reads radius, length and the origin for us
    out.push_back(ShapeKind::kCapsule);
    return true;
  }
  scan.warnings.push_back(where + ": geometry <" + type +
                          "> is not supported (supported: box, sphere, cylinder, mesh, capsule); "
                          "shape dropped");
  return false;
}

void scan_link(tinyxml2::XMLElement* link, int& materials, Scan& scan) {
  const char* name_attr = link->Attribute("name");
  if (!name_attr) return;  // urdfdom reports the missing name
  const std::string name = name_attr;
  const bool first = scan.links.find(name) == scan.links.end();
  LinkScan& ls = scan.links[name];
  if (first) scan.link_order.push_back(name);
  int inertials = 0;
  std::vector<tinyxml2::XMLElement*> removed;
  for (tinyxml2::XMLElement* c = link->FirstChildElement(); c; c = c->NextSiblingElement()) {
    const std::string tag = c->Name();
    if (tag == "inertial") {
      if (++inertials > 1) {
        scan.warnings.push_back("link '" + name +
                                "': only the first <inertial> is used; the "
                                "<inertial> at " +
                                line_of(c) + " is ignored");
      }
      for (const tinyxml2::XMLElement* i = c->FirstChildElement(); i; i = i->NextSiblingElement()) {
        const std::string t = i->Name();
        if (t != "origin" && t != "mass" && t != "inertia") {
          scan.warnings.push_back("link '" + name + "': <inertial> child <" + t + "> (" +
                                  line_of(i) + ") is not supported and is ignored");
        }
      }
    } else if (tag == "visual") {
      if (!scan_shape(c, name, "visual", ls.visual, materials, scan)) removed.push_back(c);
    } else if (tag == "collision") {
      if (!scan_shape(c, name, "collision", ls.collision, materials, scan)) removed.push_back(c);
    } else {
      scan.warnings.push_back("link '" + name + "': <" + tag + "> (" + line_of(c) +
                              ") is not supported and is ignored");
    }
  }
  for (tinyxml2::XMLElement* e : removed) link->DeleteChild(e);
}

void scan_joint(const tinyxml2::XMLElement* joint, Scan& scan) {
  const std::string name = attr(joint, "name");
  const std::string who = "joint '" + name + "'";
  const tinyxml2::XMLElement* parent = joint->FirstChildElement("parent");
  const tinyxml2::XMLElement* child = joint->FirstChildElement("child");
  scan.joints.push_back({name, parent ? attr(parent, "link") : "", child ? attr(child, "link") : "",
                         joint->GetLineNum()});
  for (const tinyxml2::XMLElement* c = joint->FirstChildElement(); c; c = c->NextSiblingElement()) {
    const std::string tag = c->Name();
    if (tag == "origin" || tag == "parent" || tag == "child" || tag == "axis" || tag == "limit") {
      continue;
    }
    if (tag == "mimic") {
      std::string how;
      if (c->Attribute("multiplier")) how += "multiplier " + attr(c, "multiplier");
      if (c->Attribute("offset"))
        how += std::string(how.empty() ? "" : ", ") + "offset " + attr(c, "offset");
      scan.warnings.push_back(who + ": mimic of '" + attr(c, "joint") + "'" +
                              (how.empty() ? "" : " (" + how + ")") +
                              " is not supported; the joint moves independently");
    } else if (tag == "dynamics" || tag == "safety_controller" || tag == "calibration") {
      std::string attrs;
      for (const tinyxml2::XMLAttribute* a = c->FirstAttribute(); a; a = a->Next()) {
        attrs += std::string(" ") + a->Name();
      }
      scan.warnings.push_back(who + ": <" + tag + attrs + "> is ignored");
    } else {
      scan.warnings.push_back(who + ": <" + tag + "> (" + line_of(c) +
                              ") is not supported and is ignored");
    }
  }
}

// Joint names are unique: urdfdom refuses a repeated name without saying where; every definition
// is named here by its line.
void check_joint_names(Scan& scan) {
  std::unordered_map<std::string, std::vector<int>> lines_of;
  std::vector<std::string> names;  // in document order of their first definition
  for (const JointScan& j : scan.joints) {
    if (j.name.empty()) continue;  // urdfdom reports the missing name
    std::vector<int>& lines = lines_of[j.name];
    if (lines.empty()) names.push_back(j.name);
    lines.push_back(j.line);
  }
  for (const std::string& name : names) {
    const std::vector<int>& lines = lines_of[name];
    if (lines.size() < 2) continue;
    std::string where;
    for (size_t k = 0; k < lines.size(); ++k) {
      where += (k == 0 ? "" : k + 1 == lines.size() ? " and " : ", ") + std::to_string(lines[k]);
    }
    const std::string times = lines.size() == 2 ? "twice" : std::to_string(lines.size()) + " times";
    scan.errors.push_back("joint '" + name + "' is defined " + times + " (lines " + where +
                          ") (rule: joint names are unique)");
  }
}

// The links must form a tree. Checked before urdfdom runs: urdfdom keeps only the last of several
// parent joints of a link, and on a cycle without a root it fails after building a reference
// cycle of shared_ptrs that is never freed.
void check_topology(Scan& scan) {
  std::unordered_map<std::string, std::vector<const JointScan*>> parents_of;  // child → joints
  std::vector<std::string> children;  // in document order of their first parent joint
  for (const JointScan& j : scan.joints) {
    if (j.parent.empty() || j.child.empty()) continue;  // urdfdom reports the missing link
    auto& list = parents_of[j.child];
    if (list.empty()) children.push_back(j.child);
    list.push_back(&j);
  }
  for (const std::string& child : children) {
    const auto& list = parents_of[child];
    if (list.size() < 2) continue;
    std::string names;
    for (const JointScan* j : list) {
      names += (names.empty() ? "'" : ", '") + j->name + "' (line " + std::to_string(j->line) + ")";
    }
    scan.errors.push_back("link '" + child + "' is the child of " + std::to_string(list.size()) +
                          " joints " + names +
                          " (rule: a link has at most one parent joint; the links form a tree)");
  }
  if (!scan.errors.empty()) return;
  // walk up from every link; meeting the current path again closes a cycle
  enum Mark { kUnseen, kOnPath, kDone };
  std::unordered_map<std::string, Mark> mark;
  for (const std::string& start : children) {
    std::vector<std::string> path;
    std::string link = start;
    while (mark[link] == kUnseen && parents_of.count(link)) {
      mark[link] = kOnPath;
      path.push_back(link);
      link = parents_of[link].front()->parent;
    }
    if (mark[link] == kOnPath) {
      const auto first = std::find(path.begin(), path.end(), link);
      std::string links, joints;
      for (auto it = first; it != path.end(); ++it) {
        links += (links.empty() ? "'" : ", '") + *it + "'";
        joints += (joints.empty() ? "'" : ", '") + parents_of[*it].front()->name + "'";
      }
      scan.errors.push_back("links " + links + " form a cycle through joints " + joints +
                            " (rule: the links form a tree, no cycles)");
    }
    for (const std::string& l : path) mark[l] = kDone;
  }
}

}  // namespace

Scan scan_document(tinyxml2::XMLElement* robot) {
  Scan scan;
  std::map<std::string, TagCount> ignored;  // top-level elements we do not read
  int materials = 0;
  int links = 0;
  for (tinyxml2::XMLElement* c = robot->FirstChildElement(); c; c = c->NextSiblingElement()) {
    const std::string tag = c->Name();
    if (tag == "link") {
      if (++links > core::kMaxLinks) {
        // count the rest without scanning them, so the message gives the real size
        for (tinyxml2::XMLElement* r = c->NextSiblingElement("link"); r;
             r = r->NextSiblingElement("link")) {
          ++links;
        }
        scan.errors.push_back("model has " + std::to_string(links) + " links (rule: at most " +
                              std::to_string(core::kMaxLinks) + " links)");
        return scan;
      }
      scan_link(c, materials, scan);
    } else if (tag == "joint") {
      scan_joint(c, scan);
    } else if (tag == "material") {
      ++materials;
    } else {
      count_tag(ignored, c);
    }
  }
  // a repeated joint name is reported alone: the tree checks would name the same joints again
  const size_t errors_before = scan.errors.size();
  check_joint_names(scan);
  if (scan.errors.size() == errors_before) check_topology(scan);
  if (materials > 0) {
    scan.warnings.push_back(std::to_string(materials) +
                            " <material> elements are ignored (colours and textures are not "
                            "imported)");
  }
  for (const auto& [tag, t] : ignored) {
    scan.warnings.push_back("<" + tag + "> elements are ignored (" + std::to_string(t.count) +
                            " found, the first at line " + std::to_string(t.first_line) + ")");
  }
  return scan;
}

}  // namespace io::urdf_internal
