#include "io/character_json.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <utility>

#include "io/atomic_file.hpp"
#include "core/model_builder.hpp"

namespace io {

using namespace core;  // io reads and writes core's types

namespace {

using Json = nlohmann::json;

// at most this many errors and warnings are reported; the rest are counted
constexpr size_t kMaxReported = 100;
// a range needs no more vertices than its triangles have corners
constexpr size_t kMaxRangeVertices = 3 * static_cast<size_t>(kMaxRangeTriangles);
// range triangles over all joints of a file (the builder's range preprocessing grows with the
// square of a range's triangles, so a file of many maximal ranges would take minutes)
constexpr size_t kMaxRangeTrianglesPerFile = 32768;
// axes and quaternions within this distance of unit length (squared norm) are kept bit for bit
constexpr double kUnitTolerance = 1e-14;
// hand-authored quaternions may be this far from unit length; they are normalized
constexpr double kQuaternionNormTolerance = 1e-3;

// ---------------------------------------------------------------------------------------------
// JSON pointers (RFC 6901) and message helpers

std::string pointer_token(std::string_view key) {
  std::string out;
  out.reserve(key.size());
  for (char c : key) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}
std::string at(const std::string& ptr, std::string_view key) {
  return ptr + "/" + pointer_token(key);
}
std::string at(const std::string& ptr, size_t index) { return ptr + "/" + std::to_string(index); }
std::string shown(const std::string& ptr) { return ptr.empty() ? "document root" : ptr; }

// Escapes control bytes and bytes outside ASCII, so a message never carries raw binary.
std::string printable(std::string_view s, size_t max_len = 200) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (size_t i = 0; i < s.size() && i < max_len; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x20 || c >= 0x7f) {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    } else {
      out += static_cast<char>(c);
    }
  }
  if (s.size() > max_len) out += "...";
  return out;
}
std::string in_quotes(std::string_view s) { return "'" + printable(s, 80) + "'"; }

const char* kind_of(const Json& j) {
  switch (j.type()) {
    case Json::value_t::null:
      return "null";
    case Json::value_t::boolean:
      return "a boolean";
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float:
      return "a number";
    case Json::value_t::string:
      return "a string";
    case Json::value_t::array:
      return "an array";
    case Json::value_t::object:
      return "an object";
    case Json::value_t::binary:
      return "binary data";
    case Json::value_t::discarded:
      return "nothing";
  }
  return "an unknown value";
}

std::string fmt(double x) {
  if (x == 0) x = 0.0;  // no "-0.0" in files or messages
  return Json(x).dump();
}

// 1-based line and column (in characters, not bytes) of a byte offset.
std::pair<size_t, size_t> line_column(const std::string& text, size_t offset) {
  offset = std::min(offset, text.size());
  size_t line = 1, column = 1;
  for (size_t i = 0; i < offset; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      ++line;
      column = 1;
    } else if ((c & 0xC0) != 0x80) {  // UTF-8 continuation bytes do not start a character
      ++column;
    }
  }
  return {line, column};
}

// Byte offset of the first bracket that opens nesting level kMaxJsonDepth + 1 (outside strings).
size_t depth_overflow_offset(const std::string& text) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth) return i;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return text.size();
}

// ---------------------------------------------------------------------------------------------
// Parsing: a SAX handler that builds the document while enforcing the depth and size limits and
// rejecting duplicate keys (nlohmann's own DOM parser silently keeps the last one).

struct ParseFailure {
  enum class Kind { kNone, kSyntax, kDepth, kStructure } kind = Kind::kNone;
  size_t position = 0;  // characters read when the syntax error was found
  std::string pointer;
  std::string message;
};

class DomBuilder final : public nlohmann::json_sax<Json> {
 public:
  Json root;
  ParseFailure failure;

  bool null() override { return add(Json(nullptr)) != nullptr; }
  bool boolean(bool b) override { return add(Json(b)) != nullptr; }
  bool number_integer(number_integer_t v) override { return add(Json(v)) != nullptr; }
  bool number_unsigned(number_unsigned_t v) override { return add(Json(v)) != nullptr; }
  bool number_float(number_float_t v, const string_t&) override { return add(Json(v)) != nullptr; }
  bool string(string_t& s) override { return add(Json(s)) != nullptr; }
  bool binary(binary_t&) override {
    fail(ParseFailure::Kind::kStructure, pointer_of_new(), "binary values are not JSON");
    return false;
  }
  bool start_object(std::size_t) override { return open(Json::object()); }
  bool key(string_t& k) override {
    Json& obj = *stack_.back();
    if (obj.contains(k)) {
      fail(ParseFailure::Kind::kStructure, at(pointer_of_top(), k),
           "duplicate key (rule: the keys of an object are unique)");
      return false;
    }
    keys_.back() = k;
    slot_ = &obj[k];
    return true;
  }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(Json::array()); }
  bool end_array() override { return close(); }
  bool parse_error(std::size_t position,
                   const std::string&,
                   const nlohmann::detail::exception& ex) override {
    failure.kind = ParseFailure::Kind::kSyntax;
    failure.position = position;
    failure.message = ex.what();
    return false;
  }

 private:
  void fail(ParseFailure::Kind kind, std::string ptr, std::string message) {
    failure.kind = kind;
    failure.pointer = std::move(ptr);
    failure.message = std::move(message);
  }
  // pointer of the innermost open container
  std::string pointer_of_top() const {
    std::string p;
    for (size_t l = 0; l + 1 < stack_.size(); ++l) {
      if (stack_[l]->is_array())
        p = at(p, stack_[l]->size() - 1);
      else
        p = at(p, keys_[l]);
    }
    return p;
  }
  // pointer of the value about to be added
  std::string pointer_of_new() const {
    if (stack_.empty()) return "";
    const Json& top = *stack_.back();
    return top.is_array() ? at(pointer_of_top(), top.size()) : at(pointer_of_top(), keys_.back());
  }
  Json* add(Json&& v) {
    if (++count_ > kMaxJsonValues) {
      fail(ParseFailure::Kind::kStructure, pointer_of_new(),
           "the document holds more than " + std::to_string(kMaxJsonValues) +
               " values (rule: at most " + std::to_string(kMaxJsonValues) + ")");
      return nullptr;
    }
    if (stack_.empty()) {
      root = std::move(v);
      return &root;
    }
    Json& top = *stack_.back();
    if (top.is_array()) {
      auto& arr = top.get_ref<Json::array_t&>();
      arr.push_back(std::move(v));
      return &arr.back();
    }
    *slot_ = std::move(v);
    return slot_;
  }
  bool open(Json&& container) {
    if (stack_.size() >= static_cast<size_t>(kMaxJsonDepth)) {
      fail(ParseFailure::Kind::kDepth, pointer_of_new(),
           "arrays and objects nest deeper than " + std::to_string(kMaxJsonDepth) +
               " levels (rule: at most " + std::to_string(kMaxJsonDepth) + ")");
      return false;
    }
    Json* p = add(std::move(container));
    if (!p) return false;
    stack_.push_back(p);
    keys_.emplace_back();
    return true;
  }
  bool close() {
    stack_.pop_back();
    keys_.pop_back();
    return true;
  }

  std::vector<Json*> stack_;       // open containers, outermost first
  std::vector<std::string> keys_;  // per open container: the key being filled (objects)
  Json* slot_ = nullptr;           // object member created by the last key()
  size_t count_ = 0;
};

// nlohmann's message without its "[json.exception.x.y] parse error at line l, column c: " head
// (the position is reported from the byte offset instead).
std::string clean_parser_message(const std::string& what) {
  std::string_view m = what;
  if (m.rfind("[json.exception.", 0) == 0) {
    const size_t close = m.find("] ");
    if (close != std::string_view::npos) m.remove_prefix(close + 2);
  }
  if (m.rfind("parse error", 0) == 0) {
    const size_t colon = m.find(": ");
    if (colon != std::string_view::npos) m.remove_prefix(colon + 2);
  }
  return printable(m);
}

// ---------------------------------------------------------------------------------------------
// Reading: typed access to the document; every problem is recorded with its pointer.

class Reader {
 public:
  std::vector<std::string> errors;
  std::vector<std::string> warnings;
  size_t range_triangles = 0;  // read so far, over all joints

  void error(const std::string& ptr, const std::string& what) {
    errors.push_back(shown(ptr) + ": " + what);
  }
  void warn(const std::string& ptr, const std::string& what) {
    warnings.push_back(shown(ptr) + ": " + what);
  }

  // Warns about every key of `obj` not in `known`.
  void check_keys(const Json& obj,
                  const std::string& ptr,
                  std::initializer_list<std::string_view> known) {
    for (const auto& [key, value] : obj.items()) {
      if (std::find(known.begin(), known.end(), key) == known.end()) {
        warn(at(ptr, key), "unknown key (ignored)");
      }
    }
  }

  static const Json* member(const Json& obj, const char* key) {
    const auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
  }

  bool object(const Json& j, const std::string& ptr) {
    if (j.is_object()) return true;
    error(ptr, std::string("expected an object, got ") + kind_of(j));
    return false;
  }
  bool array(const Json& j, const std::string& ptr, size_t max_size, const char* what) {
    if (!j.is_array()) {
      error(ptr, std::string("expected an array, got ") + kind_of(j));
      return false;
    }
    if (j.size() > max_size) {
      error(ptr, std::to_string(j.size()) + " " + what + " (rule: at most " +
                     std::to_string(max_size) + ")");
      return false;
    }
    return true;
  }

  std::optional<double> number(const Json& j, const std::string& ptr) {
    if (!j.is_number()) {
      error(ptr, std::string("expected a number, got ") + kind_of(j));
      return std::nullopt;
    }
    const double x = j.get<double>();
    if (!std::isfinite(x)) {
      error(ptr, "number is not finite (rule: numbers are finite)");
      return std::nullopt;
    }
    return x;
  }

  std::optional<long long> integer(const Json& j, const std::string& ptr) {
    if (j.is_number_unsigned()) {
      const auto u = j.get<std::uint64_t>();
      if (u > static_cast<std::uint64_t>(INT32_MAX)) {
        error(ptr, "integer " + std::to_string(u) + " is too large (rule: at most " +
                       std::to_string(INT32_MAX) + ")");
        return std::nullopt;
      }
      return static_cast<long long>(u);
    }
    if (j.is_number_integer()) return j.get<std::int64_t>();
    if (j.is_number()) {
      error(ptr, "expected an integer, got a number with a fraction or an exponent");
    } else {
      error(ptr, std::string("expected an integer, got ") + kind_of(j));
    }
    return std::nullopt;
  }

  std::optional<std::string> string(const Json& j, const std::string& ptr) {
    if (!j.is_string()) {
      error(ptr, std::string("expected a string, got ") + kind_of(j));
      return std::nullopt;
    }
    return j.get<std::string>();
  }

  // An array of exactly N numbers.
  template <int N>
  std::optional<Eigen::Matrix<double, N, 1>> vector(const Json& j, const std::string& ptr) {
    if (!j.is_array() || j.size() != static_cast<size_t>(N)) {
      error(ptr, "expected an array of " + std::to_string(N) + " numbers, got " +
                     (j.is_array() ? "an array of " + std::to_string(j.size()) + " values"
                                   : std::string(kind_of(j))));
      return std::nullopt;
    }
    Eigen::Matrix<double, N, 1> v;
    bool ok = true;
    for (int k = 0; k < N; ++k) {
      const auto x = number(j[k], at(ptr, static_cast<size_t>(k)));
      if (x)
        v[k] = *x;
      else
        ok = false;
    }
    if (!ok) return std::nullopt;
    return v;
  }

  // A row-major 3×3 matrix: an array of three arrays of three numbers.
  std::optional<Matrix3> matrix(const Json& j, const std::string& ptr) {
    if (!j.is_array() || j.size() != 3) {
      error(ptr, "expected an array of 3 rows of 3 numbers, got " +
                     (j.is_array() ? "an array of " + std::to_string(j.size()) + " values"
                                   : std::string(kind_of(j))));
      return std::nullopt;
    }
    Matrix3 M;
    bool ok = true;
    for (int r = 0; r < 3; ++r) {
      const auto row = vector<3>(j[r], at(ptr, static_cast<size_t>(r)));
      if (row)
        M.row(r) = row->transpose();
      else
        ok = false;
    }
    if (!ok) return std::nullopt;
    return M;
  }

  // A quaternion [w, x, y, z] of unit length within kQuaternionNormTolerance. A value already
  // unit to rounding is kept bit for bit; a hand-authored one is normalized.
  std::optional<Quaternion> quaternion(const Json& j, const std::string& ptr) {
    const auto v = vector<4>(j, ptr);
    if (!v) return std::nullopt;
    Quaternion q((*v)[0], (*v)[1], (*v)[2], (*v)[3]);
    const double n = q.norm();
    if (!(std::abs(n - 1.0) <= kQuaternionNormTolerance)) {
      error(ptr, "quaternion [w, x, y, z] has norm " + fmt(n) + " (rule: unit length within " +
                     fmt(kQuaternionNormTolerance) + ")");
      return std::nullopt;
    }
    if (std::abs(q.squaredNorm() - 1.0) > kUnitTolerance) q.normalize();
    return q;
  }

  // {"xyz": [x, y, z], one of "rotation" (row-major 3×3), "quaternion" [w, x, y, z] or
  // "rpy" [roll, pitch, yaw] (R = Rz(yaw) Ry(pitch) Rx(roll))}
  Transform origin(const Json& j, const std::string& ptr) {
    Transform X;
    if (!object(j, ptr)) return X;
    check_keys(j, ptr, {"xyz", "rotation", "quaternion", "rpy"});
    if (const Json* p = member(j, "xyz")) {
      if (auto v = vector<3>(*p, at(ptr, "xyz"))) X.p = *v;
    }
    const Json* rot = member(j, "rotation");
    const Json* quat = member(j, "quaternion");
    const Json* rpy = member(j, "rpy");
    if ((rot != nullptr) + (quat != nullptr) + (rpy != nullptr) > 1) {
      error(ptr, "gives more than one of rotation, quaternion and rpy (rule: at most one)");
      return X;
    }
    if (rot) {
      if (auto R = matrix(*rot, at(ptr, "rotation"))) X.R = *R;
    } else if (quat) {
      if (auto q = quaternion(*quat, at(ptr, "quaternion"))) X.R = q->toRotationMatrix();
    } else if (rpy) {
      if (auto a = vector<3>(*rpy, at(ptr, "rpy"))) {
        X.R = (Eigen::AngleAxisd((*a)[2], Vector3::UnitZ()) *
               Eigen::AngleAxisd((*a)[1], Vector3::UnitY()) *
               Eigen::AngleAxisd((*a)[0], Vector3::UnitX()))
                  .toRotationMatrix();
      }
    }
    return X;
  }
};

// What the file said about a link beyond its LinkSpec: pointers for messages and the values the
// builder would renormalize, which are restored bit for bit after building.
struct LinkInfo {
  std::string ptr;  // /links/k
  bool has_joint_name = false;
  std::optional<Vector3> axis;
  std::optional<Quaternion> range_frame;
  std::optional<Quaternion> standard_orientation;
};

bool one_dof(JointType t) { return t == JointType::kRevolute || t == JointType::kPrismatic; }

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

void read_geometry(
    Reader& rd, const Json& j, const std::string& ptr, Geometry& g, const std::string& base_dir) {
  using S = Geometry::Shape;
  if (!rd.object(j, ptr)) return;
  rd.check_keys(j, ptr, {"shape", "origin", "radius", "length", "size", "mesh", "scale"});
  const Json* shape = Reader::member(j, "shape");
  if (!shape) {
    rd.error(at(ptr, "shape"),
             "missing (rule: every shape names one of capsule, sphere, box, cylinder, mesh)");
    return;
  }
  const auto name = rd.string(*shape, at(ptr, "shape"));
  if (!name) return;
  const auto s = shape_from_string(*name);
  if (!s) {
    rd.error(at(ptr, "shape"), "unknown shape " + in_quotes(*name) +
                                   " (rule: one of capsule, sphere, box, cylinder, mesh)");
    return;
  }
  g.shape = *s;
  if (const Json* o = Reader::member(j, "origin")) g.X_LinkShape = rd.origin(*o, at(ptr, "origin"));
  const bool uses_radius = *s == S::kSphere || *s == S::kCapsule || *s == S::kCylinder;
  const bool uses_length = *s == S::kCapsule || *s == S::kCylinder;
  auto unused = [&](const char* key) {
    rd.warn(at(ptr, key), std::string("not used by a ") + to_string(*s) + " (kept)");
  };
  if (const Json* v = Reader::member(j, "radius")) {
    if (!uses_radius) unused("radius");
    if (auto x = rd.number(*v, at(ptr, "radius"))) g.radius = *x;
  }
  if (const Json* v = Reader::member(j, "length")) {
    if (!uses_length) unused("length");
    if (auto x = rd.number(*v, at(ptr, "length"))) g.length = *x;
  }
  if (const Json* v = Reader::member(j, "size")) {
    if (*s != S::kBox) unused("size");
    if (auto x = rd.vector<3>(*v, at(ptr, "size"))) g.size = *x;
  }
  if (const Json* v = Reader::member(j, "scale")) {
    if (*s != S::kMesh) unused("scale");
    if (auto x = rd.vector<3>(*v, at(ptr, "scale"))) g.scale = *x;
  }
  if (const Json* v = Reader::member(j, "mesh")) {
    if (*s != S::kMesh) unused("mesh");
    if (auto x = rd.string(*v, at(ptr, "mesh"))) {
      if (auto bad = check_mesh_path(*x)) {
        rd.error(at(ptr, "mesh"), *bad);
      } else {
        g.mesh = *x;
        std::error_code ec;
        if (*s == S::kMesh && !base_dir.empty() &&
            !std::filesystem::exists(std::filesystem::path(base_dir) / *x, ec)) {
          rd.warn(at(ptr, "mesh"),
                  "mesh file " + in_quotes(*x) + " not found in " + in_quotes(base_dir));
        }
      }
    }
  }
}

void read_shapes(Reader& rd,
                 const Json& j,
                 const std::string& ptr,
                 std::vector<Geometry>& out,
                 const std::string& base_dir) {
  if (!rd.array(j, ptr, kMaxJsonValues, "shapes")) return;
  out.resize(j.size());
  for (size_t k = 0; k < j.size(); ++k) read_geometry(rd, j[k], at(ptr, k), out[k], base_dir);
}

void read_range(
    Reader& rd, const Json& j, const std::string& ptr, SphericalRange& r, LinkInfo& info) {
  if (!rd.object(j, ptr)) return;
  rd.check_keys(j, ptr, {"frame", "vertices", "triangles"});
  if (const Json* f = Reader::member(j, "frame")) {
    if (auto q = rd.quaternion(*f, at(ptr, "frame"))) {
      r.frame = *q;
      info.range_frame = *q;
    }
  }
  if (const Json* v = Reader::member(j, "vertices")) {
    const std::string vp = at(ptr, "vertices");
    if (rd.array(*v, vp, kMaxRangeVertices, "vertices")) {
      for (size_t k = 0; k < v->size(); ++k) {
        const auto x = rd.vector<4>((*v)[k], at(vp, k));
        if (!x) continue;
        r.swing.emplace_back((*x)[0], (*x)[1]);
        r.twist_lower.push_back((*x)[2]);
        r.twist_upper.push_back((*x)[3]);
      }
    }
  }
  const size_t nvert = r.swing.size();
  if (const Json* t = Reader::member(j, "triangles")) {
    const std::string tp = at(ptr, "triangles");
    if (rd.array(*t, tp, static_cast<size_t>(kMaxRangeTriangles), "triangles")) {
      const bool was_over = rd.range_triangles > kMaxRangeTrianglesPerFile;
      rd.range_triangles += t->size();
      if (rd.range_triangles > kMaxRangeTrianglesPerFile) {
        if (!was_over) {
          rd.error(tp, "the file holds more than " + std::to_string(kMaxRangeTrianglesPerFile) +
                           " range triangles in all (rule: at most " +
                           std::to_string(kMaxRangeTrianglesPerFile) + " per file)");
        }
        return;
      }
      for (size_t k = 0; k < t->size(); ++k) {
        const Json& tri = (*t)[k];
        const std::string p = at(tp, k);
        if (!tri.is_array() || tri.size() != 3) {
          rd.error(p, "expected an array of 3 vertex indices, got " +
                          (tri.is_array() ? "an array of " + std::to_string(tri.size()) + " values"
                                          : std::string(kind_of(tri))));
          continue;
        }
        std::array<int, 3> idx{};
        bool ok = true;
        for (size_t c = 0; c < 3; ++c) {
          const auto i = rd.integer(tri[c], at(p, c));
          if (!i) {
            ok = false;
          } else if (*i < 0 || static_cast<size_t>(*i) >= nvert) {
            rd.error(at(p, c), "vertex index " + std::to_string(*i) +
                                   " is out of range (rule: 0 <= index < " + std::to_string(nvert) +
                                   ", the number of vertices)");
            ok = false;
          } else {
            idx[c] = static_cast<int>(*i);
          }
        }
        if (ok) r.triangles.push_back(idx);
      }
    }
  }
}

void read_joint(Reader& rd, const Json& j, const std::string& ptr, JointSpec& js, LinkInfo& info) {
  if (!rd.object(j, ptr)) return;
  rd.check_keys(
      j, ptr, {"name", "type", "origin", "axis", "limits", "range", "standard_orientation", "ik"});
  if (const Json* n = Reader::member(j, "name")) {
    if (auto s = rd.string(*n, at(ptr, "name"))) {
      if (s->empty()) {
        rd.error(at(ptr, "name"), "joint name is empty (omit the key to use the link name)");
      } else {
        js.name = *s;
        info.has_joint_name = true;
      }
    }
  }
  if (const Json* t = Reader::member(j, "type")) {
    if (auto s = rd.string(*t, at(ptr, "type"))) {
      if (auto type = joint_type_from_string(*s)) {
        js.type = *type;
      } else {
        rd.error(at(ptr, "type"),
                 "unknown joint type " + in_quotes(*s) +
                     " (rule: one of fixed, revolute, prismatic, spherical, free)");
      }
    }
  }
  if (const Json* o = Reader::member(j, "origin")) js.X_PJ = rd.origin(*o, at(ptr, "origin"));

  const char* type_name = to_string(js.type);
  if (const Json* a = Reader::member(j, "axis")) {
    if (!one_dof(js.type)) {
      rd.warn(at(ptr, "axis"), std::string("ignored: a ") + type_name +
                                   " joint has no axis (only revolute and prismatic joints do)");
    } else if (auto v = rd.vector<3>(*a, at(ptr, "axis"))) {
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
  if (const Json* l = Reader::member(j, "limits")) {
    const std::string lp = at(ptr, "limits");
    if (!one_dof(js.type)) {
      rd.warn(lp, std::string("ignored: a ") + type_name +
                      " joint has no limits (only revolute and prismatic joints do)");
    } else if (rd.object(*l, lp)) {
      rd.check_keys(*l, lp, {"lower", "upper", "velocity", "effort"});
      auto get = [&](const char* key, double& out) {
        if (const Json* v = Reader::member(*l, key)) {
          if (auto x = rd.number(*v, at(lp, key))) out = *x;
        }
      };
      get("lower", js.limits.lower);
      get("upper", js.limits.upper);
      get("velocity", js.limits.velocity);
      get("effort", js.limits.effort);
    }
  }
  if (const Json* r = Reader::member(j, "range")) {
    if (js.type != JointType::kSpherical) {
      rd.error(at(ptr, "range"), std::string("a ") + type_name +
                                     " joint cannot have a swing-twist range "
                                     "(rule: only spherical joints have one)");
    } else {
      read_range(rd, *r, at(ptr, "range"), js.range, info);
    }
  }
  if (const Json* s = Reader::member(j, "standard_orientation")) {
    if (js.type != JointType::kSpherical) {
      rd.warn(at(ptr, "standard_orientation"),
              std::string("ignored: a ") + type_name +
                  " joint has no standard orientation (only spherical joints do)");
    } else if (auto q = rd.quaternion(*s, at(ptr, "standard_orientation"))) {
      js.standard_orientation = *q;
      info.standard_orientation = *q;
    }
  }
  if (const Json* ik = Reader::member(j, "ik")) {
    const std::string ip = at(ptr, "ik");
    if (rd.object(*ik, ip)) {
      rd.check_keys(*ik, ip, {"weight", "gain"});
      if (const Json* w = Reader::member(*ik, "weight")) {
        if (auto x = rd.number(*w, at(ip, "weight"))) js.ik_weight = *x;
      }
      if (const Json* g = Reader::member(*ik, "gain")) {
        if (auto x = rd.number(*g, at(ip, "gain"))) js.ik_gain = *x;
      }
    }
  }
}

void read_inertial(Reader& rd, const Json& j, const std::string& ptr, LinkSpec& l) {
  if (!rd.object(j, ptr)) return;
  rd.check_keys(j, ptr, {"mass", "com", "inertia"});
  if (const Json* m = Reader::member(j, "mass")) {
    if (auto x = rd.number(*m, at(ptr, "mass"))) l.mass = *x;
  }
  if (const Json* c = Reader::member(j, "com")) {
    if (auto v = rd.vector<3>(*c, at(ptr, "com"))) l.com = *v;
  }
  if (const Json* in = Reader::member(j, "inertia")) {
    const std::string ip = at(ptr, "inertia");
    if (in->is_array()) {
      if (auto M = rd.matrix(*in, ip)) l.I_com = *M;
    } else if (rd.object(*in, ip)) {
      rd.check_keys(*in, ip, {"ixx", "iyy", "izz", "ixy", "ixz", "iyz"});
      static constexpr std::array<std::pair<const char*, std::pair<int, int>>, 6> kEntries{{
          {"ixx", {0, 0}},
          {"iyy", {1, 1}},
          {"izz", {2, 2}},
          {"ixy", {0, 1}},
          {"ixz", {0, 2}},
          {"iyz", {1, 2}},
      }};
      for (const auto& [key, rc] : kEntries) {
        if (const Json* v = Reader::member(*in, key)) {
          if (auto x = rd.number(*v, at(ip, key))) {
            l.I_com(rc.first, rc.second) = *x;
            l.I_com(rc.second, rc.first) = *x;
          }
        }
      }
    }
  }
}

void read_link(Reader& rd,
               const Json& j,
               const std::string& ptr,
               LinkSpec& l,
               LinkInfo& info,
               const std::string& base_dir) {
  info.ptr = ptr;
  if (!rd.object(j, ptr)) return;
  rd.check_keys(j, ptr,
                {"name", "parent", "display_name", "joint", "inertial", "collision", "visual"});
  if (const Json* n = Reader::member(j, "name")) {
    if (auto s = rd.string(*n, at(ptr, "name"))) {
      if (s->empty()) rd.error(at(ptr, "name"), "link name is empty (rule: names are non-empty)");
      l.name = *s;
    }
  } else {
    rd.error(at(ptr, "name"), "missing (rule: every link has a name)");
  }
  if (const Json* p = Reader::member(j, "parent"); p && !p->is_null()) {
    if (auto s = rd.string(*p, at(ptr, "parent"))) {
      if (s->empty()) {
        rd.error(at(ptr, "parent"), "parent name is empty (rule: null or no key for the root)");
      }
      l.parent = *s;
    }
  }
  if (const Json* d = Reader::member(j, "display_name")) {
    if (auto s = rd.string(*d, at(ptr, "display_name"))) l.display_name = *s;
  }
  if (const Json* jt = Reader::member(j, "joint"))
    read_joint(rd, *jt, at(ptr, "joint"), l.joint, info);
  if (const Json* in = Reader::member(j, "inertial"))
    read_inertial(rd, *in, at(ptr, "inertial"), l);
  if (const Json* c = Reader::member(j, "collision")) {
    read_shapes(rd, *c, at(ptr, "collision"), l.collision, base_dir);
  }
  if (const Json* v = Reader::member(j, "visual")) {
    read_shapes(rd, *v, at(ptr, "visual"), l.visual, base_dir);
  }
}

// Tree rules with pointers: unique names, parents that exist, one root, no cycles.
void check_structure(Reader& rd,
                     const std::vector<LinkSpec>& links,
                     const std::vector<LinkInfo>& info) {
  const size_t n = links.size();
  std::unordered_map<std::string, size_t> by_name, by_joint;
  for (size_t k = 0; k < n; ++k) {
    const LinkSpec& l = links[k];
    if (l.name.empty()) continue;
    if (auto [it, fresh] = by_name.emplace(l.name, k); !fresh) {
      rd.error(at(info[k].ptr, "name"), "link name " + in_quotes(l.name) + " is also used by " +
                                            info[it->second].ptr +
                                            " (rule: link names are unique)");
    }
    const std::string& jn = l.joint.name.empty() ? l.name : l.joint.name;
    if (auto [it, fresh] = by_joint.emplace(jn, k); !fresh) {
      const std::string p =
          info[k].has_joint_name ? at(at(info[k].ptr, "joint"), "name") : at(info[k].ptr, "name");
      rd.error(p, "joint name " + in_quotes(jn) + " is also used by the joint of " +
                      info[it->second].ptr + " (rule: joint names are unique)");
    }
  }
  if (!rd.errors.empty()) return;

  std::vector<long> parent(n, -1);
  std::vector<size_t> roots;
  for (size_t k = 0; k < n; ++k) {
    const LinkSpec& l = links[k];
    if (l.parent.empty()) {
      roots.push_back(k);
      continue;
    }
    const auto it = by_name.find(l.parent);
    if (it == by_name.end()) {
      rd.error(at(info[k].ptr, "parent"),
               "parent link " + in_quotes(l.parent) + " does not exist (rule: parents are links)");
    } else if (it->second == k) {
      rd.error(at(info[k].ptr, "parent"),
               "link " + in_quotes(l.name) + " is its own parent (rule: no cycles)");
    } else {
      parent[k] = static_cast<long>(it->second);
    }
  }
  if (roots.empty()) {
    rd.error("/links", "no link is the root (rule: exactly one link has no parent)");
  }
  for (size_t r = 1; r < roots.size(); ++r) {
    rd.error(at(info[roots[r]].ptr, "parent"),
             "missing, so link " + in_quotes(links[roots[r]].name) + " is a second root besides " +
                 info[roots[0]].ptr + " " + in_quotes(links[roots[0]].name) +
                 " (rule: exactly one link has no parent)");
  }
  if (!rd.errors.empty()) return;

  // every parent chain must reach the root; colour: 0 unseen, 1 on the current walk, 2 done
  std::vector<char> colour(n, 0);
  for (size_t k = 0; k < n; ++k) {
    std::vector<size_t> walk;
    long i = static_cast<long>(k);
    while (i >= 0 && colour[i] == 0) {
      colour[i] = 1;
      walk.push_back(static_cast<size_t>(i));
      i = parent[i];
    }
    if (i >= 0 && colour[i] == 1) {
      // the walk closed a new cycle starting at i
      const auto start = std::find(walk.begin(), walk.end(), static_cast<size_t>(i));
      std::string names;
      size_t shown_names = 0;
      for (auto w = start; w != walk.end(); ++w, ++shown_names) {
        if (shown_names == 8) {
          names += " -> ...";
          break;
        }
        names += (names.empty() ? "" : " -> ") + in_quotes(links[*w].name);
      }
      names += " -> " + in_quotes(links[static_cast<size_t>(i)].name);
      rd.error(at(info[static_cast<size_t>(i)].ptr, "parent"),
               "the parent links form a cycle " + names + " (rule: no cycles)");
    }
    for (size_t w : walk) colour[w] = 2;
  }
}

// A builder violation ("link 'x': ...", "joint 'y': ...") with the pointer of the field it is
// about; the link is looked up by name, the field by the words of the message.
std::string locate(const std::string& v,
                   const std::unordered_map<std::string, size_t>& by_name,
                   const std::unordered_map<std::string, size_t>& by_joint,
                   const std::vector<LinkInfo>& info) {
  auto find = [&](std::string_view prefix, const std::unordered_map<std::string, size_t>& names,
                  std::string_view& rest) -> long {
    if (v.rfind(prefix, 0) != 0) return -1;
    for (size_t pos = v.find("': ", prefix.size()); pos != std::string::npos;
         pos = v.find("': ", pos + 1)) {
      const auto it = names.find(v.substr(prefix.size(), pos - prefix.size()));
      if (it != names.end()) {
        rest = std::string_view(v).substr(pos + 3);
        return static_cast<long>(it->second);
      }
    }
    return -1;
  };
  auto index_after = [](std::string_view s, std::string_view word) -> std::string {
    const size_t p = s.find(word);
    if (p == std::string_view::npos) return "";
    size_t e = p + word.size();
    while (e < s.size() && s[e] >= '0' && s[e] <= '9') ++e;
    return std::string(s.substr(p + word.size(), e - p - word.size()));
  };
  auto has = [](std::string_view s, std::string_view word) {
    return s.find(word) != std::string_view::npos;
  };

  std::string_view rest;
  if (long k = find("link '", by_name, rest); k >= 0) {
    const std::string& p = info[static_cast<size_t>(k)].ptr;
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
  if (long k = find("joint '", by_joint, rest); k >= 0) {
    const std::string p = info[static_cast<size_t>(k)].ptr + "/joint";
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
  return "/links";
}

[[noreturn]] void throw_errors(const std::string& source, const std::vector<std::string>& lines) {
  std::vector<std::string> out;
  for (size_t i = 0; i < lines.size() && i < kMaxReported; ++i) {
    out.push_back(source + ": " + lines[i]);
  }
  if (lines.size() > kMaxReported) {
    out.push_back(source + ": ... and " + std::to_string(lines.size() - kMaxReported) +
                  " more errors");
  }
  throw ModelError(std::move(out));
}

std::vector<std::string> prefixed(const std::string& source, const std::vector<std::string>& in) {
  std::vector<std::string> out;
  for (size_t i = 0; i < in.size() && i < kMaxReported; ++i) out.push_back(source + ": " + in[i]);
  if (in.size() > kMaxReported) {
    out.push_back(source + ": ... and " + std::to_string(in.size() - kMaxReported) +
                  " more warnings");
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Writing: a small ordered tree, printed with short arrays and small flat objects on one line.

struct Node {
  enum class Kind { kScalar, kArray, kObject } kind = Kind::kScalar;
  std::string text;               // kScalar: serialized JSON
  std::vector<Node> items;        // kArray: the elements; kObject: the values
  std::vector<std::string> keys;  // kObject: the keys, in order

  static Node scalar(std::string t) {
    Node n;
    n.text = std::move(t);
    return n;
  }
  static Node array() {
    Node n;
    n.kind = Kind::kArray;
    return n;
  }
  static Node object() {
    Node n;
    n.kind = Kind::kObject;
    return n;
  }
  Node& add(std::string key, Node value) {
    keys.push_back(std::move(key));
    items.push_back(std::move(value));
    return items.back();
  }
  Node& push(Node value) {
    items.push_back(std::move(value));
    return items.back();
  }
  bool empty() const { return items.empty(); }
  // printed on one line: scalars, arrays of scalars, objects of at most six scalars
  bool flat() const {
    if (kind == Kind::kScalar) return true;
    if (kind == Kind::kObject && items.size() > 6) return false;
    return std::all_of(items.begin(), items.end(),
                       [](const Node& n) { return n.kind == Kind::kScalar; });
  }
};

std::string json_string(const std::string& s, const char* what) {
  try {
    return Json(s).dump();
  } catch (const Json::type_error&) {
    throw std::invalid_argument(std::string(what) + " " + in_quotes(s) +
                                " is not valid UTF-8 (rule: JSON text is UTF-8)");
  }
}

void print(const Node& n, int indent, std::string& out) {
  const std::string pad(static_cast<size_t>(indent), ' ');
  const std::string inner(static_cast<size_t>(indent) + 2, ' ');
  switch (n.kind) {
    case Node::Kind::kScalar:
      out += n.text;
      return;
    case Node::Kind::kArray:
      if (n.items.empty()) {
        out += "[]";
      } else if (n.flat()) {
        out += '[';
        for (size_t i = 0; i < n.items.size(); ++i) out += (i ? ", " : "") + n.items[i].text;
        out += ']';
      } else {
        out += "[\n";
        for (size_t i = 0; i < n.items.size(); ++i) {
          out += inner;
          print(n.items[i], indent + 2, out);
          out += i + 1 < n.items.size() ? ",\n" : "\n";
        }
        out += pad + "]";
      }
      return;
    case Node::Kind::kObject:
      if (n.items.empty()) {
        out += "{}";
      } else if (n.flat()) {
        out += '{';
        for (size_t i = 0; i < n.items.size(); ++i) {
          out += (i ? ", " : "") + Json(n.keys[i]).dump() + ": " + n.items[i].text;
        }
        out += '}';
      } else {
        out += "{\n";
        for (size_t i = 0; i < n.items.size(); ++i) {
          out += inner + Json(n.keys[i]).dump() + ": ";
          print(n.items[i], indent + 2, out);
          out += i + 1 < n.items.size() ? ",\n" : "\n";
        }
        out += pad + "}";
      }
      return;
  }
}

Node num(double x) { return Node::scalar(fmt(x)); }
Node str(const std::string& s, const char* what) { return Node::scalar(json_string(s, what)); }
template <typename Vec>
Node vec(const Vec& v) {
  Node a = Node::array();
  for (int k = 0; k < v.size(); ++k) a.push(num(v[k]));
  return a;
}
Node quat(const Quaternion& q) { return vec(Eigen::Vector4d(q.w(), q.x(), q.y(), q.z())); }
Node rows(const Matrix3& M) {
  Node a = Node::array();
  for (int r = 0; r < 3; ++r) a.push(vec(Eigen::Vector3d(M.row(r).transpose())));
  return a;
}
bool is_identity(const Quaternion& q) { return q.coeffs() == Quaternion::Identity().coeffs(); }

// {"xyz", "rotation"} of a transform; nullopt for the identity.
std::optional<Node> origin_node(const Transform& X) {
  Node o = Node::object();
  if (X.p != Vector3::Zero()) o.add("xyz", vec(X.p));
  if (X.R != Matrix3::Identity()) o.add("rotation", rows(X.R));
  if (o.empty()) return std::nullopt;
  return o;
}

double step_ulps(double x, int d) {
  for (int s = 0; s < std::abs(d); ++s) x = std::nextafter(x, d > 0 ? kInfinity : -kInfinity);
  return x;
}
double no_negative_zero(double x) { return x == 0 ? 0.0 : x; }

// Mirrors the builder's inertia rules: symmetric, positive semidefinite, triangle inequality.
bool plausible_inertia(const Matrix3& I) {
  const double scale = std::max(1e-12, I.cwiseAbs().maxCoeff());
  if ((I - I.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) return false;
  const Eigen::Vector3d e = Eigen::SelfAdjointEigenSolver<Matrix3>(I).eigenvalues();
  return e.minCoeff() >= -1e-9 * scale && e(0) + e(1) >= e(2) - 1e-6 * scale;
}

// Doubles in numeric order as integers (-0 and +0 share a key), for searching over doubles.
std::int64_t order_key(double x) {
  std::int64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b >= 0 ? b : std::numeric_limits<std::int64_t>::min() - b;
}
double from_order_key(std::int64_t k) {
  const std::int64_t b = k >= 0 ? k : std::numeric_limits<std::int64_t>::min() - k;
  double x;
  std::memcpy(&x, &b, sizeof x);
  return x;
}

// All finite doubles a with fl(a + P) == T. a -> fl(a + P) is monotone, so they form an interval;
// a solution is looked for next to T - P, then both ends are found by galloping and bisection.
struct Interval {
  double lo = 0, hi = 0;
};
std::optional<Interval> sum_preimage(double P, double T) {
  auto ok = [&](std::int64_t k) { return from_order_key(k) + P == T; };
  const double a0 = T - P;
  std::optional<std::int64_t> seed;
  for (int d : {0, -1, 1, -2, 2, -3, 3}) {
    const double a = step_ulps(a0, d);
    if (std::isfinite(a) && ok(order_key(a))) {
      seed = order_key(a);
      break;
    }
  }
  if (!seed) return std::nullopt;
  const std::int64_t kmin = order_key(-std::numeric_limits<double>::max());
  const std::int64_t kmax = order_key(std::numeric_limits<double>::max());
  auto edge = [&](bool up) {
    std::int64_t good = *seed, bad = 0;
    const std::int64_t limit = up ? kmax : kmin;
    for (std::uint64_t step = 1;; step *= 2) {
      const std::uint64_t room =
          up ? static_cast<std::uint64_t>(limit) - static_cast<std::uint64_t>(good)
             : static_cast<std::uint64_t>(good) - static_cast<std::uint64_t>(limit);
      const std::int64_t next = room <= step ? limit
                                             : (up ? good + static_cast<std::int64_t>(step)
                                                   : good - static_cast<std::int64_t>(step));
      if (!ok(next)) {
        bad = next;
        break;
      }
      good = next;
      if (next == limit) return good;
    }
    for (;;) {
      const std::int64_t mid = std::midpoint(good, bad);
      if (mid == good || mid == bad) return good;
      (ok(mid) ? good : bad) = mid;
    }
  };
  return Interval{from_order_key(edge(false)), from_order_key(edge(true))};
}

// Centre of mass c and inertia about it, I_c, such that SpatialInertia::from_com(m, c, I_c)
// reproduces T bit for bit and the builder accepts I_c. The plain answer (h / m, and I_O minus
// the parallel-axis term) can miss in the last bit, and where the parallel-axis term dwarfs the
// inertia it leaves rounding residue the builder rejects (a point mass with a slightly negative
// moment). Then nearby doubles are searched: each c with fl(m c_k) = h_k, and for it the box of
// all I_c with fl(I_c + P) = I_O entry by entry (P the parallel-axis term of that c), from which
// the first plausible of a few candidates is taken (see below), each clamped into the box.
struct InertiaForm {
  Vector3 com = Vector3::Zero();
  Matrix3 I = Matrix3::Zero();
};
InertiaForm inertia_form(const SpatialInertia& T) {
  InertiaForm plain;
  if (!(T.mass > 0)) {
    plain.I = T.I_O.unaryExpr(&no_negative_zero);  // I_O = I_c exactly when m = 0
    return plain;
  }
  plain.com = T.com().unaryExpr(&no_negative_zero);
  plain.I = T.inertia_about_com().unaryExpr(&no_negative_zero);
  if (SpatialInertia::from_com(T.mass, plain.com, plain.I) == T && plausible_inertia(plain.I)) {
    return plain;
  }

  std::array<std::vector<double>, 3> candidates;
  for (int k = 0; k < 3; ++k) {
    const double c = T.h[k] / T.mass;
    for (int d : {0, -1, 1, -2, 2, -3, 3, -4, 4}) {
      const double x = no_negative_zero(step_ulps(c, d));
      if (T.mass * x == T.h[k]) candidates[k].push_back(x);
    }
    if (candidates[k].empty()) return plain;
  }
  std::optional<InertiaForm> exact_only;
  for (double cx : candidates[0]) {
    for (double cy : candidates[1]) {
      for (double cz : candidates[2]) {
        InertiaForm f;
        f.com = Vector3(cx, cy, cz);
        const Matrix3 P = SpatialInertia::from_com(T.mass, f.com, Matrix3::Zero()).I_O;
        std::array<std::array<Interval, 3>, 3> box;
        bool solvable = true;
        for (int i = 0; i < 3 && solvable; ++i) {
          for (int j = 0; j < 3 && solvable; ++j) {
            const auto iv = sum_preimage(P(i, j), T.I_O(i, j));
            solvable = iv.has_value();
            if (iv) box[i][j] = *iv;
          }
        }
        if (!solvable) continue;
        auto into_box = [&](const Matrix3& G) {
          Matrix3 I;
          for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
              I(i, j) = no_negative_zero(std::clamp(G(i, j), box[i][j].lo, box[i][j].hi));
            }
          }
          return I;
        };
        // candidates: the plain answer, the same without products of inertia, and both with
        // equal principal moments d, d taken from each moment in the box and large enough to
        // dominate the products (Gershgorin: the moments lie in [d - r, d + r], so d >= 3r
        // satisfies the triangle inequality)
        const Matrix3 G_plain = T.I_O - P;
        Matrix3 G_diagonal = Matrix3::Zero();
        G_diagonal.diagonal() = G_plain.diagonal();
        std::vector<Matrix3> guesses{G_plain, G_diagonal};
        for (const Matrix3& base : {G_diagonal, G_plain}) {
          const Matrix3 B = into_box(base);
          double r = 0;
          for (int i = 0; i < 3; ++i) {
            r = std::max(r, B.row(i).cwiseAbs().sum() - std::abs(B(i, i)));
          }
          for (double d :
               {B(0, 0), B(1, 1), B(2, 2), 4 * r, std::max(B.diagonal().maxCoeff(), 4 * r)}) {
            Matrix3 G = base;
            G.diagonal().setConstant(d);
            guesses.push_back(G);
          }
        }
        for (const Matrix3& G : guesses) {
          f.I = into_box(G);
          if (!(SpatialInertia::from_com(T.mass, f.com, f.I) == T)) continue;
          if (plausible_inertia(f.I)) return f;
          if (!exact_only) exact_only = f;
        }
      }
    }
  }
  return exact_only ? *exact_only : plain;
}

Node inertial_node(const SpatialInertia& S) {
  const InertiaForm f = inertia_form(S);
  Node o = Node::object();
  o.add("mass", num(S.mass));
  if (f.com != Vector3::Zero()) o.add("com", vec(f.com));
  if (f.I == f.I.transpose()) {
    Node in = Node::object();
    in.add("ixx", num(f.I(0, 0)));
    in.add("iyy", num(f.I(1, 1)));
    in.add("izz", num(f.I(2, 2)));
    in.add("ixy", num(f.I(0, 1)));
    in.add("ixz", num(f.I(0, 2)));
    in.add("iyz", num(f.I(1, 2)));
    o.add("inertia", std::move(in));
  } else {
    o.add("inertia", rows(f.I));  // not symmetric to the last bit: all nine entries
  }
  return o;
}

Node geometry_node(const Geometry& g) {
  using S = Geometry::Shape;
  Node o = Node::object();
  o.add("shape", Node::scalar(Json(to_string(g.shape)).dump()));
  if (auto org = origin_node(g.X_LinkShape)) o.add("origin", std::move(*org));
  const bool uses_radius =
      g.shape == S::kSphere || g.shape == S::kCapsule || g.shape == S::kCylinder;
  const bool uses_length = g.shape == S::kCapsule || g.shape == S::kCylinder;
  // fields a shape does not use are written only when set, so nothing in the model is lost
  if (uses_radius || g.radius != 0) o.add("radius", num(g.radius));
  if (uses_length || g.length != 0) o.add("length", num(g.length));
  if (g.shape == S::kBox || g.size != Vector3::Zero()) o.add("size", vec(g.size));
  if (g.shape == S::kMesh || !g.mesh.empty()) o.add("mesh", str(g.mesh, "mesh path"));
  if (g.scale != Vector3::Ones()) o.add("scale", vec(g.scale));
  return o;
}

Node joint_node(const Model& m, int i) {
  const JointType type = m.joint_type[i];
  const std::string& jname = m.joint_name[i];
  Node j = Node::object();
  if (jname != m.link_name[i]) j.add("name", str(jname, "joint name"));
  j.add("type", Node::scalar(Json(to_string(type)).dump()));
  if (auto org = origin_node(m.X_PJ[i])) j.add("origin", std::move(*org));
  if (one_dof(type)) {
    j.add("axis", vec(m.axis[i]));
    const JointLimits& L = m.limits[i];
    auto unrepresentable = [&](const char* what) {
      throw std::invalid_argument("joint " + in_quotes(jname) + ": " + what +
                                  " cannot be written (rule: JSON numbers are finite; an "
                                  "omitted lower limit is -inf, an omitted upper limit +inf)");
    };
    if (L.lower == kInfinity) unrepresentable("lower limit +inf");
    if (L.upper == -kInfinity) unrepresentable("upper limit -inf");
    if (L.velocity == -kInfinity || L.effort == -kInfinity) unrepresentable("a limit of -inf");
    Node l = Node::object();
    if (std::isfinite(L.lower)) l.add("lower", num(L.lower));
    if (std::isfinite(L.upper)) l.add("upper", num(L.upper));
    if (std::isfinite(L.velocity)) l.add("velocity", num(L.velocity));
    if (std::isfinite(L.effort)) l.add("effort", num(L.effort));
    if (!l.empty()) j.add("limits", std::move(l));
  }
  if (type == JointType::kSpherical) {
    const SphericalRange& r = m.spherical_range[i];
    if (!is_identity(r.frame) || !r.swing.empty() || !r.triangles.empty()) {
      Node rn = Node::object();
      if (!is_identity(r.frame)) rn.add("frame", quat(r.frame));
      Node verts = Node::array();
      for (size_t k = 0; k < r.swing.size(); ++k) {
        const double lo = k < r.twist_lower.size() ? r.twist_lower[k] : 0.0;
        const double hi = k < r.twist_upper.size() ? r.twist_upper[k] : 0.0;
        verts.push(vec(Eigen::Vector4d(r.swing[k].x(), r.swing[k].y(), lo, hi)));
      }
      rn.add("vertices", std::move(verts));
      Node tris = Node::array();
      for (const auto& t : r.triangles) {
        Node tri = Node::array();
        for (int idx : t) tri.push(Node::scalar(std::to_string(idx)));
        tris.push(std::move(tri));
      }
      rn.add("triangles", std::move(tris));
      j.add("range", std::move(rn));
    }
    if (!is_identity(m.standard_orientation[i])) {
      j.add("standard_orientation", quat(m.standard_orientation[i]));
    }
  }
  const double weight = m.ik_weight[i];
  if (weight != 1.0 || m.ik_gain[i]) {
    Node ik = Node::object();
    if (weight != 1.0) ik.add("weight", num(weight));
    if (m.ik_gain[i]) ik.add("gain", num(*m.ik_gain[i]));
    j.add("ik", std::move(ik));
  }
  return j;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

LoadResult load_character_json_string(const std::string& text,
                                      const std::string& source_name,
                                      const std::string& base_dir) {
  const std::string& src = source_name;
  if (text.size() > kMaxCharacterJsonBytes) {
    throw ModelError(
        {src + ": " + std::to_string(text.size()) + " bytes is too large (rule: at most 64 MiB)"});
  }

  // parse
  DomBuilder dom;
  if (!Json::sax_parse(text, &dom, Json::input_format_t::json, /*strict=*/true)) {
    const ParseFailure& f = dom.failure;
    switch (f.kind) {
      case ParseFailure::Kind::kSyntax: {
        // nlohmann counts the characters read, including the one that failed
        const auto [line, column] = line_column(text, f.position > 0 ? f.position - 1 : 0);
        std::string msg = clean_parser_message(f.message);
        if (text.empty()) msg = "the file is empty (rule: a JSON object)";
        throw ModelError({src + ": line " + std::to_string(line) + ", column " +
                          std::to_string(column) + ": " + msg});
      }
      case ParseFailure::Kind::kDepth: {
        const auto [line, column] = line_column(text, depth_overflow_offset(text));
        throw ModelError({src + ": line " + std::to_string(line) + ", column " +
                          std::to_string(column) + ": " + shown(f.pointer) + ": " + f.message});
      }
      case ParseFailure::Kind::kStructure:
        throw ModelError({src + ": " + shown(f.pointer) + ": " + f.message});
      case ParseFailure::Kind::kNone:
        break;
    }
    throw ModelError({src + ": the JSON parser stopped without a reason"});
  }
  const Json& doc = dom.root;

  // header
  Reader rd;
  if (!rd.object(doc, "")) throw_errors(src, rd.errors);
  rd.check_keys(doc, "", {"format", "version", "name", "gravity", "links"});
  if (const Json* f = Reader::member(doc, "format")) {
    if (auto s = rd.string(*f, "/format"); s && *s != kCharacterFormat) {
      rd.error("/format", "is " + in_quotes(*s) + " (rule: \"" + kCharacterFormat + "\")");
    }
  } else {
    rd.error("/format", std::string("missing (rule: \"format\": \"") + kCharacterFormat +
                            "\" identifies a character file)");
  }
  if (const Json* v = Reader::member(doc, "version")) {
    if (auto n = rd.integer(*v, "/version"); n && *n != kCharacterFormatVersion) {
      rd.error("/version", "version " + std::to_string(*n) + " is not supported (rule: " +
                               std::to_string(kCharacterFormatVersion) + ")");
    }
  } else {
    rd.error("/version",
             "missing (rule: \"version\": " + std::to_string(kCharacterFormatVersion) + ")");
  }
  if (!rd.errors.empty()) throw_errors(src, rd.errors);

  std::string name = std::filesystem::path(src).stem().string();
  if (const Json* n = Reader::member(doc, "name")) {
    if (auto s = rd.string(*n, "/name")) name = *s;
  }
  Vector3 gravity(0, -9.81, 0);
  if (const Json* g = Reader::member(doc, "gravity")) {
    if (auto v = rd.vector<3>(*g, "/gravity")) gravity = *v;
  }

  // links: counted before anything is built
  const Json* links_json = Reader::member(doc, "links");
  if (!links_json) {
    rd.error("/links", "missing (rule: a character has an array of links)");
    throw_errors(src, rd.errors);
  }
  if (!rd.array(*links_json, "/links", static_cast<size_t>(kMaxLinks), "links")) {
    throw_errors(src, rd.errors);
  }
  if (links_json->empty()) {
    rd.error("/links", "no links (rule: at least one link)");
    throw_errors(src, rd.errors);
  }
  const size_t n = links_json->size();
  std::vector<LinkSpec> links(n);
  std::vector<LinkInfo> info(n);
  for (size_t k = 0; k < n; ++k) {
    read_link(rd, (*links_json)[k], at(std::string("/links"), k), links[k], info[k], base_dir);
  }
  if (!rd.errors.empty()) throw_errors(src, rd.errors);
  check_structure(rd, links, info);
  if (!rd.errors.empty()) throw_errors(src, rd.errors);

  // build: the builder checks the physical rules; its messages get the field's pointer
  ModelBuilder b(name);
  b.set_gravity(gravity);
  b.set_source_dir(base_dir);
  for (const LinkSpec& l : links) b.add_link(l);
  std::shared_ptr<const Model> built;
  try {
    built = b.finalize();
  } catch (const ModelError& e) {
    std::unordered_map<std::string, size_t> by_name, by_joint;
    for (size_t k = 0; k < n; ++k) {
      by_name.emplace(links[k].name, k);
      by_joint.emplace(links[k].joint.name.empty() ? links[k].name : links[k].joint.name, k);
    }
    std::vector<std::string> lines;
    for (const std::string& v : e.violations()) {
      lines.push_back(locate(v, by_name, by_joint, info) + ": " + v);
    }
    throw_errors(src, lines);
  }

  // the inertia about the link frame must stay finite (m |c|² can overflow where m and c do not)
  std::unordered_map<std::string, int> index;
  for (int i = 1; i < built->njoints; ++i) index.emplace(built->link_name[i], i);
  for (size_t k = 0; k < n; ++k) {
    const SpatialInertia& S = built->inertia[index.at(links[k].name)];
    if (!S.h.allFinite() || !S.I_O.allFinite()) {
      rd.error(at(info[k].ptr, "inertial"),
               "the inertia about the link frame overflows (rule: mass × com and mass × |com|² "
               "plus the inertia are finite)");
    }
  }
  if (!rd.errors.empty()) throw_errors(src, rd.errors);

  // the builder renormalizes axes and quaternions, which can move the last bit of a value that
  // is already unit; restore the file's bits so that load(write(m)) == m
  auto model = std::make_shared<Model>(*built);
  for (size_t k = 0; k < n; ++k) {
    const int i = index.at(links[k].name);
    const LinkInfo& li = info[k];
    if (li.axis && one_dof(model->joint_type[i]) &&
        std::abs(li.axis->squaredNorm() - 1.0) <= kUnitTolerance) {
      model->axis[i] = *li.axis;
      model->axis_index[i] = -1;
      for (int a = 0; a < 3; ++a) {
        if (model->axis[i] == Vector3::Unit(a)) model->axis_index[i] = a;
      }
    }
    if (model->joint_type[i] == JointType::kSpherical) {
      if (li.range_frame) model->spherical_range[i].frame = *li.range_frame;
      if (li.standard_orientation) model->standard_orientation[i] = *li.standard_orientation;
    }
  }

  LoadResult result;
  result.model = std::move(model);
  result.warnings = prefixed(src, rd.warnings);
  return result;
}

LoadResult load_character_json_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) {
    throw ModelError({path + ": cannot open the file" + (ec ? ": " + ec.message() : "")});
  }
  if (!fs::is_regular_file(st)) {
    throw ModelError({path + ": not a regular file (rule: a character file is a plain file)"});
  }
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw ModelError({path + ": cannot read the file size: " + ec.message()});
  if (size > kMaxCharacterJsonBytes) {
    throw ModelError(
        {path + ": the file is " + std::to_string(size) + " bytes (rule: at most 64 MiB)"});
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ModelError({path + ": cannot open the file"});
  std::string text(static_cast<size_t>(size), '\0');
  in.read(text.data(), static_cast<std::streamsize>(size));
  text.resize(static_cast<size_t>(in.gcount()));
  if (in.bad()) throw ModelError({path + ": read error"});

  fs::path dir = fs::absolute(fs::path(path), ec).parent_path();
  if (ec) dir = fs::path(path).parent_path();
  return load_character_json_string(text, path, dir.lexically_normal().string());
}

std::string write_character_json(const Model& m) {
  Node doc = Node::object();
  doc.add("format", Node::scalar(Json(kCharacterFormat).dump()));
  doc.add("version", Node::scalar(std::to_string(kCharacterFormatVersion)));
  doc.add("name", str(m.name, "model name"));
  doc.add("gravity", vec(m.gravity));
  Node links = Node::array();
  for (int i = 1; i < m.njoints; ++i) {
    Node l = Node::object();
    l.add("name", str(m.link_name[i], "link name"));
    if (m.parent[i] > 0) l.add("parent", str(m.link_name[m.parent[i]], "link name"));
    if (!m.display_name[i].empty()) l.add("display_name", str(m.display_name[i], "display name"));
    l.add("joint", joint_node(m, i));
    const SpatialInertia& S = m.inertia[i];
    if (S.mass != 0 || S.h != Vector3::Zero() || S.I_O != Matrix3::Zero()) {
      l.add("inertial", inertial_node(S));
    }
    for (const auto& [key, shapes] :
         {std::pair{"collision", &m.collision[i]}, std::pair{"visual", &m.visual[i]}}) {
      if (shapes->empty()) continue;
      Node arr = Node::array();
      for (const Geometry& g : *shapes) arr.push(geometry_node(g));
      l.add(key, std::move(arr));
    }
    links.push(std::move(l));
  }
  doc.add("links", std::move(links));
  std::string out;
  print(doc, 0, out);
  out += '\n';
  return out;
}

void save_character_json_file(const Model& model, const std::string& path) {
  write_file_atomically(path, write_character_json(model));
}

}  // namespace io
