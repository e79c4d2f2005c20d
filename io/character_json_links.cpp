// One link object of a character file to a LinkSpec: name and parent, the joint (type, origin,
// axis, limits, swing-twist range, standard orientation, IK gains), the inertial block and the
// collision and visual shapes. Every problem is recorded with its pointer; reading goes on, so
// one pass reports every mistake of a file.
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <system_error>
#include <utility>

#include "io/character_json_internal.hpp"

namespace io::character_json {

using namespace core;  // io reads and writes core's types

namespace {

// {"xyz": [x, y, z], one of "rotation" (row-major 3×3), "quaternion" [w, x, y, z] or
// "rpy" [roll, pitch, yaw] (R = Rz(yaw) Ry(pitch) Rx(roll))}
Transform read_origin(CharacterReader& rd, const JsonField& j) {
  Transform X;
  if (!rd.object(j)) return X;
  rd.warn_unknown_keys(j, {"xyz", "rotation", "quaternion", "rpy"});
  if (const JsonField p = j["xyz"]) {
    if (auto v = rd.vector<3>(p)) X.p = *v;
  }
  const JsonField rot = j["rotation"], quat = j["quaternion"], rpy = j["rpy"];
  if (rot.exists() + quat.exists() + rpy.exists() > 1) {
    rd.fail(j, "gives more than one of rotation, quaternion and rpy (rule: at most one)");
    return X;
  }
  if (rot) {
    if (auto R = rd.matrix(rot)) X.R = *R;
  } else if (quat) {
    if (auto q = rd.quaternion(quat)) X.R = q->toRotationMatrix();
  } else if (rpy) {
    if (auto a = rd.vector<3>(rpy)) {
      X.R = (Eigen::AngleAxisd((*a)[2], Vector3::UnitZ()) *
             Eigen::AngleAxisd((*a)[1], Vector3::UnitY()) *
             Eigen::AngleAxisd((*a)[0], Vector3::UnitX()))
                .toRotationMatrix();
    }
  }
  return X;
}

// Mesh references stay inside the model's folder.
std::optional<std::string> check_mesh_path(const std::string& mesh) {
  if (mesh.empty()) return "mesh path is empty";
  if (mesh.find('\0') != std::string::npos) return "mesh path contains a NUL character";
  if (mesh.find("://") != std::string::npos) {
    return "mesh path is a URI (rule: a path relative to the character file's folder)";
  }
  const std::filesystem::path p(mesh);
  if (p.is_absolute() || p.has_root_name() || p.has_root_directory() || mesh[0] == '\\') {
    return "mesh path is absolute (rule: a path relative to the character file's folder)";
  }
  for (const auto& part : p) {
    if (part == "..") return "mesh path leaves the character file's folder (rule: no '..')";
  }
  return std::nullopt;
}

void read_mesh(CharacterReader& rd,
               const JsonField& m,
               Geometry& g,
               bool is_mesh,
               const std::string& base_dir) {
  const auto x = rd.string(m);
  if (!x) return;
  if (auto bad = check_mesh_path(*x)) {
    rd.fail(m, *bad);
    return;
  }
  g.mesh = *x;
  std::error_code ec;
  if (is_mesh && !base_dir.empty() &&
      !std::filesystem::exists(std::filesystem::path(base_dir) / *x, ec)) {
    rd.warn(m, "mesh file " + in_quotes(*x) + " not found in " + in_quotes(base_dir));
  }
}

void read_geometry(CharacterReader& rd,
                   const JsonField& j,
                   Geometry& g,
                   const std::string& base_dir) {
  using S = Geometry::Shape;
  if (!rd.object(j)) return;
  rd.warn_unknown_keys(j, {"shape", "origin", "radius", "length", "size", "mesh", "scale"});
  const JsonField shape = j["shape"];
  if (!shape) {
    rd.fail(shape, "missing (rule: every shape names one of capsule, sphere, box, cylinder, mesh)");
    return;
  }
  const auto name = rd.string(shape);
  if (!name) return;
  const auto s = shape_from_string(*name);
  if (!s) {
    rd.fail(shape, "unknown shape " + in_quotes(*name) +
                       " (rule: one of capsule, sphere, box, cylinder, mesh)");
    return;
  }
  g.shape = *s;
  if (const JsonField o = j["origin"]) g.X_LinkShape = read_origin(rd, o);
  const bool uses_radius = *s == S::kSphere || *s == S::kCapsule || *s == S::kCylinder;
  const bool uses_length = *s == S::kCapsule || *s == S::kCylinder;
  // a key the shape does not use is kept, with a warning
  auto read = [&](const char* key, bool used, auto&& store) {
    const JsonField f = j[key];
    if (!f) return;
    if (!used) rd.warn(f, std::string("not used by a ") + to_string(*s) + " (kept)");
    store(f);
  };
  read("radius", uses_radius, [&](const JsonField& f) {
    if (auto x = rd.number(f)) g.radius = *x;
  });
  read("length", uses_length, [&](const JsonField& f) {
    if (auto x = rd.number(f)) g.length = *x;
  });
  read("size", *s == S::kBox, [&](const JsonField& f) {
    if (auto x = rd.vector<3>(f)) g.size = *x;
  });
  read("scale", *s == S::kMesh, [&](const JsonField& f) {
    if (auto x = rd.vector<3>(f)) g.scale = *x;
  });
  read("mesh", *s == S::kMesh,
       [&](const JsonField& f) { read_mesh(rd, f, g, *s == S::kMesh, base_dir); });
}

void read_shapes(CharacterReader& rd,
                 const JsonField& j,
                 std::vector<Geometry>& out,
                 const std::string& base_dir) {
  if (!rd.array(j, kMaxJsonValues, "shapes")) return;
  out.resize(j.size());
  for (std::size_t k = 0; k < j.size(); ++k) read_geometry(rd, j[k], out[k], base_dir);
}

// One triangle [i, j, k] of vertex indices below `nvert`.
std::optional<std::array<int, 3>> read_triangle(CharacterReader& rd,
                                                const JsonField& tri,
                                                std::size_t nvert) {
  if (!tri->is_array() || tri->size() != 3) {
    rd.fail(tri, "expected an array of 3 vertex indices, got " +
                     (tri->is_array() ? "an array of " + std::to_string(tri->size()) + " values"
                                      : rd.kind(*tri)));
    return std::nullopt;
  }
  std::array<int, 3> idx{};
  bool ok = true;
  for (std::size_t c = 0; c < 3; ++c) {
    const auto i =
        rd.integer(tri[c], std::numeric_limits<int>::min(), std::numeric_limits<int>::max());
    if (!i) {
      ok = false;
    } else if (*i < 0 || static_cast<std::size_t>(*i) >= nvert) {
      rd.fail(tri[c], "vertex index " + std::to_string(*i) +
                          " is out of range (rule: 0 <= index < " + std::to_string(nvert) +
                          ", the number of vertices)");
      ok = false;
    } else {
      idx[c] = static_cast<int>(*i);
    }
  }
  if (!ok) return std::nullopt;
  return idx;
}

void read_triangles(CharacterReader& rd, const JsonField& t, SphericalRange& r) {
  if (!rd.array(t, static_cast<std::size_t>(kMaxRangeTriangles), "triangles")) return;
  const bool was_over = rd.range_triangles > kMaxRangeTrianglesPerFile;
  rd.range_triangles += t.size();
  if (rd.range_triangles > kMaxRangeTrianglesPerFile) {
    if (!was_over) {  // said once, not once per joint
      const std::string cap = std::to_string(kMaxRangeTrianglesPerFile);
      rd.fail(t, "the file holds more than " + cap + " range triangles in all (rule: at most " +
                     cap + " per file)");
    }
    return;
  }
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (auto tri = read_triangle(rd, t[k], r.swing.size())) r.triangles.push_back(*tri);
  }
}

void read_range(CharacterReader& rd, const JsonField& j, SphericalRange& r, LinkInfo& info) {
  if (!rd.object(j)) return;
  rd.warn_unknown_keys(j, {"frame", "vertices", "triangles"});
  if (const JsonField f = j["frame"]) {
    if (auto q = rd.quaternion(f)) {
      r.frame = *q;
      info.range_frame = *q;
    }
  }
  if (const JsonField v = j["vertices"]) {
    if (rd.array(v, kMaxRangeVertices, "vertices")) {
      for (std::size_t k = 0; k < v.size(); ++k) {
        const auto x = rd.vector<4>(v[k]);
        if (!x) continue;
        r.swing.emplace_back((*x)[0], (*x)[1]);
        r.twist_lower.push_back((*x)[2]);
        r.twist_upper.push_back((*x)[3]);
      }
    }
  }
  if (const JsonField t = j["triangles"]) read_triangles(rd, t, r);
}

// "axis" and "limits", which only revolute and prismatic joints have
void read_axis_and_limits(CharacterReader& rd, const JsonField& j, JointSpec& js, LinkInfo& info) {
  const std::string type_name = to_string(js.type);
  if (const JsonField a = j["axis"]) {
    if (!one_dof(js.type)) {
      rd.warn(a, "ignored: a " + type_name +
                     " joint has no axis (only revolute and prismatic joints do)");
    } else if (auto v = rd.vector<3>(a)) {
      // scale a hand-authored axis such as [0, 0, 2] to unit length first (stableNorm does not
      // overflow for huge components); one too short to have a direction is left to the builder
      const double n = v->stableNorm();
      if (std::isfinite(n) && n >= 1e-9 && std::abs(v->squaredNorm() - 1.0) > kUnitTolerance) {
        *v /= n;
      }
      js.axis = *v;
      info.axis = *v;
    }
  }
  if (const JsonField l = j["limits"]) {
    if (!one_dof(js.type)) {
      rd.warn(l, "ignored: a " + type_name +
                     " joint has no limits (only revolute and prismatic joints do)");
    } else if (rd.object(l)) {
      rd.warn_unknown_keys(l, {"lower", "upper", "velocity", "effort"});
      for (auto [key, out] :
           {std::pair{"lower", &js.limits.lower}, std::pair{"upper", &js.limits.upper},
            std::pair{"velocity", &js.limits.velocity}, std::pair{"effort", &js.limits.effort}}) {
        if (const JsonField v = l[key]) {
          if (auto x = rd.number(v)) *out = *x;
        }
      }
    }
  }
}

// "range" and "standard_orientation", which only spherical joints have
void read_spherical(CharacterReader& rd, const JsonField& j, JointSpec& js, LinkInfo& info) {
  const std::string type_name = to_string(js.type);
  if (const JsonField r = j["range"]) {
    if (js.type != JointType::kSpherical) {
      rd.fail(r, "a " + type_name +
                     " joint cannot have a swing-twist range "
                     "(rule: only spherical joints have one)");
    } else {
      read_range(rd, r, js.range, info);
    }
  }
  if (const JsonField s = j["standard_orientation"]) {
    if (js.type != JointType::kSpherical) {
      rd.warn(s, "ignored: a " + type_name +
                     " joint has no standard orientation (only spherical joints do)");
    } else if (auto q = rd.quaternion(s)) {
      js.standard_orientation = *q;
      info.standard_orientation = *q;
    }
  }
}

void read_joint(CharacterReader& rd, const JsonField& j, JointSpec& js, LinkInfo& info) {
  if (!rd.object(j)) return;
  rd.warn_unknown_keys(
      j, {"name", "type", "origin", "axis", "limits", "range", "standard_orientation", "ik"});
  if (const JsonField n = j["name"]) {
    if (auto s = rd.string(n)) {
      if (s->empty()) {
        rd.fail(n, "joint name is empty (omit the key to use the link name)");
      } else {
        js.name = *s;
        info.has_joint_name = true;
      }
    }
  }
  if (const JsonField t = j["type"]) {
    if (auto s = rd.string(t)) {
      if (auto type = joint_type_from_string(*s)) {
        js.type = *type;
      } else {
        rd.fail(t, "unknown joint type " + in_quotes(*s) +
                       " (rule: one of fixed, revolute, prismatic, spherical, free)");
      }
    }
  }
  if (const JsonField o = j["origin"]) js.X_PJ = read_origin(rd, o);
  read_axis_and_limits(rd, j, js, info);
  read_spherical(rd, j, js, info);
  if (const JsonField ik = j["ik"]) {
    if (rd.object(ik)) {
      rd.warn_unknown_keys(ik, {"weight", "gain"});
      if (const JsonField w = ik["weight"]) {
        if (auto x = rd.number(w)) js.ik_weight = *x;
      }
      if (const JsonField g = ik["gain"]) {
        if (auto x = rd.number(g)) js.ik_gain = *x;
      }
    }
  }
}

void read_inertial(CharacterReader& rd, const JsonField& j, LinkSpec& l) {
  if (!rd.object(j)) return;
  rd.warn_unknown_keys(j, {"mass", "com", "inertia"});
  if (const JsonField m = j["mass"]) {
    if (auto x = rd.number(m)) l.mass = *x;
  }
  if (const JsonField c = j["com"]) {
    if (auto v = rd.vector<3>(c)) l.com = *v;
  }
  const JsonField in = j["inertia"];
  if (!in) return;
  if (in->is_array()) {
    if (auto M = rd.matrix(in)) l.I_com = *M;
    return;
  }
  if (!rd.object(in)) return;
  rd.warn_unknown_keys(in, {"ixx", "iyy", "izz", "ixy", "ixz", "iyz"});
  static constexpr std::array<std::pair<const char*, std::pair<int, int>>, 6> kEntries{{
      {"ixx", {0, 0}},
      {"iyy", {1, 1}},
      {"izz", {2, 2}},
      {"ixy", {0, 1}},
      {"ixz", {0, 2}},
      {"iyz", {1, 2}},
  }};
  for (const auto& [key, rc] : kEntries) {
    if (const JsonField v = in[key]) {
      if (auto x = rd.number(v)) {
        l.I_com(rc.first, rc.second) = *x;
        l.I_com(rc.second, rc.first) = *x;
      }
    }
  }
}

}  // namespace

void read_link(CharacterReader& rd,
               const JsonField& j,
               LinkSpec& l,
               LinkInfo& info,
               const std::string& base_dir) {
  info.ptr = j.pointer();
  if (!rd.object(j)) return;
  rd.warn_unknown_keys(
      j, {"name", "parent", "display_name", "joint", "inertial", "collision", "visual"});
  if (const JsonField n = j["name"]) {
    if (auto s = rd.string(n)) {
      if (s->empty()) rd.fail(n, "link name is empty (rule: names are non-empty)");
      l.name = *s;
    }
  } else {
    rd.fail(n, "missing (rule: every link has a name)");
  }
  if (const JsonField p = j["parent"]; p.given()) {
    if (auto s = rd.string(p)) {
      if (s->empty()) rd.fail(p, "parent name is empty (rule: null or no key for the root)");
      l.parent = *s;
    }
  }
  if (const JsonField d = j["display_name"]) {
    if (auto s = rd.string(d)) l.display_name = *s;
  }
  if (const JsonField jt = j["joint"]) read_joint(rd, jt, l.joint, info);
  if (const JsonField in = j["inertial"]) read_inertial(rd, in, l);
  if (const JsonField c = j["collision"]) read_shapes(rd, c, l.collision, base_dir);
  if (const JsonField v = j["visual"]) read_shapes(rd, v, l.visual, base_dir);
}

}  // namespace io::character_json
