// The rules of a character's link tree, checked with pointers before anything is built, and the
// pointer of the field each ModelBuilder violation is about.
#include <algorithm>
#include <string_view>

#include "io/character_json_internal.hpp"

namespace io::character_json {

using namespace core;  // io reads and writes core's types

namespace {

// Link names and joint names are unique.
void check_names(CharacterReader& rd,
                 const std::vector<LinkSpec>& links,
                 const std::vector<LinkInfo>& info,
                 std::unordered_map<std::string, std::size_t>& by_name) {
  std::unordered_map<std::string, std::size_t> by_joint;
  for (std::size_t k = 0; k < links.size(); ++k) {
    const LinkSpec& l = links[k];
    if (l.name.empty()) continue;
    if (auto [it, fresh] = by_name.emplace(l.name, k); !fresh) {
      rd.fail_at(json_pointer(info[k].ptr, "name"), "link name " + in_quotes(l.name) +
                                                        " is also used by " + info[it->second].ptr +
                                                        " (rule: link names are unique)");
    }
    const std::string& jn = l.joint.name.empty() ? l.name : l.joint.name;
    if (auto [it, fresh] = by_joint.emplace(jn, k); !fresh) {
      const std::string p = info[k].has_joint_name
                                ? json_pointer(json_pointer(info[k].ptr, "joint"), "name")
                                : json_pointer(info[k].ptr, "name");
      rd.fail_at(p, "joint name " + in_quotes(jn) + " is also used by the joint of " +
                        info[it->second].ptr + " (rule: joint names are unique)");
    }
  }
}

// Parents exist and exactly one link has none; returns each link's parent index (-1: none).
std::vector<long> check_parents(CharacterReader& rd,
                                const std::vector<LinkSpec>& links,
                                const std::vector<LinkInfo>& info,
                                const std::unordered_map<std::string, std::size_t>& by_name) {
  const std::size_t n = links.size();
  std::vector<long> parent(n, -1);
  std::vector<std::size_t> roots;
  for (std::size_t k = 0; k < n; ++k) {
    const LinkSpec& l = links[k];
    if (l.parent.empty()) {
      roots.push_back(k);
      continue;
    }
    const auto it = by_name.find(l.parent);
    const std::string p = json_pointer(info[k].ptr, "parent");
    if (it == by_name.end()) {
      rd.fail_at(
          p, "parent link " + in_quotes(l.parent) + " does not exist (rule: parents are links)");
    } else if (it->second == k) {
      rd.fail_at(p, "link " + in_quotes(l.name) + " is its own parent (rule: no cycles)");
    } else {
      parent[k] = static_cast<long>(it->second);
    }
  }
  if (roots.empty()) {
    rd.fail_at("/links", "no link is the root (rule: exactly one link has no parent)");
  }
  for (std::size_t r = 1; r < roots.size(); ++r) {
    rd.fail_at(json_pointer(info[roots[r]].ptr, "parent"),
               "missing, so link " + in_quotes(links[roots[r]].name) +
                   " is a second root besides " + info[roots[0]].ptr + " " +
                   in_quotes(links[roots[0]].name) + " (rule: exactly one link has no parent)");
  }
  return parent;
}

// Every parent chain reaches the root; each cycle is reported once, at its first link.
void check_cycles(CharacterReader& rd,
                  const std::vector<LinkSpec>& links,
                  const std::vector<LinkInfo>& info,
                  const std::vector<long>& parent) {
  const std::size_t n = links.size();
  // colour: 0 unseen, 1 on the current walk, 2 done
  std::vector<char> colour(n, 0);
  for (std::size_t k = 0; k < n; ++k) {
    std::vector<std::size_t> walk;
    long i = static_cast<long>(k);
    while (i >= 0 && colour[i] == 0) {
      colour[i] = 1;
      walk.push_back(static_cast<std::size_t>(i));
      i = parent[i];
    }
    if (i >= 0 && colour[i] == 1) {
      // the walk closed a new cycle starting at i
      const auto start = std::find(walk.begin(), walk.end(), static_cast<std::size_t>(i));
      std::string names;
      std::size_t shown_names = 0;
      for (auto w = start; w != walk.end(); ++w, ++shown_names) {
        if (shown_names == 8) {
          names += " -> ...";
          break;
        }
        names += (names.empty() ? "" : " -> ") + in_quotes(links[*w].name);
      }
      names += " -> " + in_quotes(links[static_cast<std::size_t>(i)].name);
      rd.fail_at(json_pointer(info[static_cast<std::size_t>(i)].ptr, "parent"),
                 "the parent links form a cycle " + names + " (rule: no cycles)");
    }
    for (std::size_t w : walk) colour[w] = 2;
  }
}

// the digits right after `word` in `s`; empty when `word` is not there
std::string index_after(std::string_view s, std::string_view word) {
  const std::size_t p = s.find(word);
  if (p == std::string_view::npos) return "";
  std::size_t e = p + word.size();
  while (e < s.size() && s[e] >= '0' && s[e] <= '9') ++e;
  return std::string(s.substr(p + word.size(), e - p - word.size()));
}

bool has(std::string_view s, std::string_view word) {
  return s.find(word) != std::string_view::npos;
}

// the field of link `p` a "link '...': <rest>" violation is about
std::string link_field(const std::string& p, std::string_view rest) {
  for (const char* kind : {"collision", "visual"}) {
    const std::string idx = index_after(rest, std::string(kind) + " shape ");
    if (idx.empty()) continue;
    const std::string sp = p + "/" + kind + "/" + idx;
    if (has(rest, "pose")) return sp + "/origin";
    if (has(rest, "radius")) return sp + "/radius";
    if (has(rest, "length")) return sp + "/length";
    if (has(rest, "box sizes")) return sp + "/size";
    if (has(rest, "mesh")) return sp + "/mesh";
    return sp;
  }
  if (has(rest, "centre of mass")) return p + "/inertial/com";
  if (has(rest, "inertia") || has(rest, "principal moments")) return p + "/inertial/inertia";
  if (has(rest, "mass")) return p + "/inertial/mass";
  if (has(rest, "parent") || has(rest, "cycle")) return p + "/parent";
  if (has(rest, "name")) return p + "/name";
  return p;
}

// the field of joint `p` a "joint '...': <rest>" violation is about
std::string joint_field(const std::string& p, std::string_view rest) {
  if (std::string i = index_after(rest, "range vertex "); !i.empty()) {
    return p + "/range/vertices/" + i;
  }
  if (std::string i = index_after(rest, "range triangle "); !i.empty()) {
    return p + "/range/triangles/" + i;
  }
  if (has(rest, "range frame")) return p + "/range/frame";
  if (has(rest, "range")) return p + "/range";
  if (has(rest, "placement")) return p + "/origin";
  if (has(rest, "axis")) return p + "/axis";
  if (has(rest, "limit")) return p + "/limits";
  if (has(rest, "standard orientation")) return p + "/standard_orientation";
  if (has(rest, "IK weight")) return p + "/ik/weight";
  if (has(rest, "IK gain")) return p + "/ik/gain";
  if (has(rest, "name")) return p + "/name";
  return p;
}

// The link a violation starting with `prefix` ("link '") names, found among `names` (names may
// hold "': ", so every split is tried); `rest` is the text after the name.
long named(const std::string& v,
           std::string_view prefix,
           const std::unordered_map<std::string, std::size_t>& names,
           std::string_view& rest) {
  if (v.rfind(prefix, 0) != 0) return -1;
  for (std::size_t pos = v.find("': ", prefix.size()); pos != std::string::npos;
       pos = v.find("': ", pos + 1)) {
    const auto it = names.find(v.substr(prefix.size(), pos - prefix.size()));
    if (it != names.end()) {
      rest = std::string_view(v).substr(pos + 3);
      return static_cast<long>(it->second);
    }
  }
  return -1;
}

}  // namespace

void check_structure(CharacterReader& rd,
                     const std::vector<LinkSpec>& links,
                     const std::vector<LinkInfo>& info) {
  std::unordered_map<std::string, std::size_t> by_name;
  check_names(rd, links, info, by_name);
  if (!rd.errors().empty()) return;
  const std::vector<long> parent = check_parents(rd, links, info, by_name);
  if (!rd.errors().empty()) return;
  check_cycles(rd, links, info, parent);
}

std::string locate_violation(const std::string& v,
                             const std::unordered_map<std::string, std::size_t>& by_name,
                             const std::unordered_map<std::string, std::size_t>& by_joint,
                             const std::vector<LinkInfo>& info) {
  std::string_view rest;
  if (long k = named(v, "link '", by_name, rest); k >= 0) {
    return link_field(info[static_cast<std::size_t>(k)].ptr, rest);
  }
  if (long k = named(v, "joint '", by_joint, rest); k >= 0) {
    return joint_field(info[static_cast<std::size_t>(k)].ptr + "/joint", rest);
  }
  return "/links";
}

}  // namespace io::character_json
