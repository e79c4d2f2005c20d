#include "server/mesh_binary.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

namespace server {
namespace {

template <typename T>
void append(std::string& out, const T* data, std::size_t count) {
  const std::size_t bytes = sizeof(T) * count;
  const std::size_t at = out.size();
  out.resize(at + bytes);
  if (bytes) std::memcpy(out.data() + at, data, bytes);
  out.resize((out.size() + 3) / 4 * 4, '\0');  // every array starts 4-byte aligned
}

}  // namespace

std::string encode_mesh_binary(const core::SkinnedMesh& mesh) {
  const std::size_t n = mesh.positions.size();
  const bool normals = mesh.normals.size() == n && n > 0;
  nlohmann::json bones = nlohmann::json::array();
  for (int link : mesh.bones) bones.push_back(link - 1);  // character.links omits the world
  nlohmann::json inverse_bind = nlohmann::json::array();
  for (const core::Transform& X : mesh.inverse_bind) {
    nlohmann::json m = nlohmann::json::array();
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) {
        if (c < 3)
          m.push_back(r < 3 ? X.R(r, c) : 0.0);
        else
          m.push_back(r < 3 ? X.p(r) : 1.0);
      }
    }
    inverse_bind.push_back(std::move(m));
  }
  nlohmann::json parts = nlohmann::json::array();
  for (const core::MeshPart& p : mesh.parts) {
    parts.push_back(
        {{"first", p.first_triangle},
         {"count", p.triangle_count},
         {"base_color", {p.base_color[0], p.base_color[1], p.base_color[2], p.base_color[3]}},
         {"texture", p.texture}});
  }
  nlohmann::json textures = nlohmann::json::array();
  for (const core::MeshTexture& t : mesh.textures) {
    textures.push_back({{"mime_type", t.mime_type}, {"bytes", t.bytes.size()}});
  }
  const nlohmann::json header{
      {"name", mesh.name},
      {"vertices", n},
      {"triangles", mesh.triangles.size()},
      {"normals", normals},
      {"bones", bones},
      {"inverse_bind", inverse_bind},
      {"base_color",
       {mesh.base_color[0], mesh.base_color[1], mesh.base_color[2], mesh.base_color[3]}},
      {"uvs", !mesh.uvs.empty()},
      {"parts", parts},
      {"textures", textures}};
  std::string text = header.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  text.resize((text.size() + 3) / 4 * 4, ' ');

  std::string out = "PDMS";
  const auto length = static_cast<std::uint32_t>(text.size());
  append(out, &length, 1);
  out += text;
  std::vector<float> floats;
  floats.reserve(4 * n);
  for (const auto& p : mesh.positions) floats.insert(floats.end(), {p.x(), p.y(), p.z()});
  append(out, floats.data(), floats.size());
  if (normals) {
    floats.clear();
    for (const auto& v : mesh.normals) floats.insert(floats.end(), {v.x(), v.y(), v.z()});
    append(out, floats.data(), floats.size());
  }
  std::vector<std::uint32_t> indices;
  indices.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    for (int k : t) indices.push_back(static_cast<std::uint32_t>(k));
  }
  append(out, indices.data(), indices.size());
  std::vector<std::uint16_t> joints;
  joints.reserve(4 * n);
  for (const auto& j : mesh.joints) {
    for (int k : j) joints.push_back(static_cast<std::uint16_t>(k));
  }
  append(out, joints.data(), joints.size());
  floats.clear();
  for (const auto& w : mesh.weights) floats.insert(floats.end(), w.begin(), w.end());
  append(out, floats.data(), floats.size());
  floats.clear();
  for (const auto& uv : mesh.uvs) floats.insert(floats.end(), {uv.x(), uv.y()});
  append(out, floats.data(), floats.size());
  for (const core::MeshTexture& t : mesh.textures) append(out, t.bytes.data(), t.bytes.size());
  return out;
}

namespace {

[[noreturn]] void refuse_mesh(const std::string& source, const std::string& what) {
  throw std::runtime_error(source + ": " + what);
}

// Reads the arrays in order, each 4-byte aligned, never past the end.
class Reader {
 public:
  Reader(const std::string& bytes, std::size_t at, const std::string& source)
      : bytes_(bytes), at_(at), source_(source) {}

  template <typename T>
  std::vector<T> take(std::size_t count, const char* field) {
    const std::size_t size = sizeof(T) * count;
    if (count > bytes_.size() / sizeof(T) || size > bytes_.size() - at_) {
      refuse_mesh(source_, std::string(field) + ": " + std::to_string(count) +
                               " values run past the end of the file (rule: the header's counts)");
    }
    std::vector<T> out(count);
    if (size) std::memcpy(out.data(), bytes_.data() + at_, size);
    at_ = std::min(bytes_.size(), at_ + (size + 3) / 4 * 4);
    return out;
  }
  std::size_t bytes_left() const { return bytes_.size() - at_; }

 private:
  const std::string& bytes_;
  std::size_t at_;
  const std::string& source_;
};

template <typename T>
void check_finite(const std::vector<T>& values, const std::string& source, const char* field) {
  for (T v : values) {
    if (!std::isfinite(v)) refuse_mesh(source, std::string(field) + ": a value is not finite");
  }
}

// a number the header gives as an unsigned integer that fits an int
int small_count(const nlohmann::json& j, const std::string& source, const std::string& field) {
  if (!j.is_number_unsigned() || j.get<std::uint64_t>() > std::numeric_limits<int>::max()) {
    refuse_mesh(source, field + ": not a count (rule: an integer from 0 to 2^31 - 1)");
  }
  return j.get<int>();
}

// Texture coordinates, parts and textures (absent in meshes written before them: one part of
// base_color, untextured).
void read_materials(const nlohmann::json& h,
                    Reader& in,
                    const std::string& source,
                    core::SkinnedMesh& mesh) {
  const std::size_t n = mesh.positions.size();
  if (h.contains("uvs") && !h["uvs"].is_boolean()) refuse_mesh(source, "uvs: not a bool");
  for (const char* field : {"parts", "textures"}) {
    if (h.contains(field) && !h[field].is_array()) {
      refuse_mesh(source, std::string(field) + ": not an array");
    }
  }
  if (h.value("parts", nlohmann::json::array()).size() > mesh.triangles.size() ||
      h.value("textures", nlohmann::json::array()).size() > in.bytes_left()) {
    refuse_mesh(source, "parts, textures: more than the mesh can hold");
  }
  for (const auto& p : h.value("parts", nlohmann::json::array())) {
    const std::string at = "parts[" + std::to_string(mesh.parts.size()) + "]";
    if (!p.is_object() || !p.contains("first") || !p.contains("count")) {
      refuse_mesh(source, at + ": not an object with first and count");
    }
    core::MeshPart part;
    part.first_triangle = small_count(p["first"], source, at + ".first");
    part.triangle_count = small_count(p["count"], source, at + ".count");
    const nlohmann::json color = p.value("base_color", nlohmann::json());
    if (!color.is_array() || color.size() != 4)
      refuse_mesh(source, at + ".base_color: not 4 numbers");
    for (int k = 0; k < 4; ++k) {
      if (!color[k].is_number()) refuse_mesh(source, at + ".base_color: not 4 numbers");
      part.base_color[k] = color[k].get<float>();
    }
    const nlohmann::json texture = p.value("texture", nlohmann::json(-1));
    if (!texture.is_number_integer() || texture.get<long long>() < -1 ||
        texture.get<long long>() > std::numeric_limits<int>::max()) {
      refuse_mesh(source, at + ".texture: not a texture index or -1");
    }
    part.texture = texture.get<int>();
    mesh.parts.push_back(part);
  }
  if (h.value("uvs", false)) {
    const std::vector<float> uvs = in.take<float>(2 * n, "uvs");
    check_finite(uvs, source, "uvs");
    for (std::size_t v = 0; v < n; ++v) mesh.uvs.emplace_back(uvs[2 * v], uvs[2 * v + 1]);
  }
  for (const auto& t : h.value("textures", nlohmann::json::array())) {
    const std::string at = "textures[" + std::to_string(mesh.textures.size()) + "]";
    if (!t.is_object() || !t.contains("mime_type") || !t["mime_type"].is_string() ||
        !t.contains("bytes") || !t["bytes"].is_number_unsigned()) {
      refuse_mesh(source, at + ": not an object with mime_type and bytes");
    }
    const std::vector<char> image = in.take<char>(t["bytes"].get<std::size_t>(), "textures");
    mesh.textures.push_back({t["mime_type"].get<std::string>(), {image.begin(), image.end()}});
  }
  const std::string e = core::check_mesh_materials(mesh);
  if (!e.empty()) refuse_mesh(source, e);
}

}  // namespace

core::SkinnedMesh decode_mesh_binary(const std::string& bytes,
                                     int nlinks,
                                     const std::string& source) {
  if (bytes.size() < 8 || bytes.compare(0, 4, "PDMS") != 0) {
    refuse_mesh(source, "not a pindrag mesh (rule: it starts with PDMS and a header length)");
  }
  std::uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 4, 4);
  if (length > bytes.size() - 8) refuse_mesh(source, "header: longer than the file");
  const nlohmann::json h = nlohmann::json::parse(bytes.substr(8, length), nullptr, false);
  if (h.is_discarded() || !h.is_object()) refuse_mesh(source, "header: not a JSON object");
  const auto count = [&](const char* field) -> std::size_t {
    const auto it = h.find(field);
    if (it == h.end() || !it->is_number_unsigned()) {
      refuse_mesh(source, std::string(field) + ": a count (rule: a non-negative integer)");
    }
    return it->get<std::size_t>();
  };
  const std::size_t n = count("vertices"), t = count("triangles");
  if (!h.contains("normals") || !h["normals"].is_boolean())
    refuse_mesh(source, "normals: not a bool");
  if (!h.contains("bones") || !h["bones"].is_array()) refuse_mesh(source, "bones: not an array");
  if (!h.contains("inverse_bind") || !h["inverse_bind"].is_array() ||
      h["inverse_bind"].size() != h["bones"].size()) {
    refuse_mesh(source, "inverse_bind: not one matrix per bone");
  }
  core::SkinnedMesh mesh;
  if (h.contains("name") && h["name"].is_string()) mesh.name = h["name"];
  for (const auto& b : h["bones"]) {
    if (!b.is_number_integer() || b.get<long long>() < 0 || b.get<long long>() + 1 >= nlinks) {
      refuse_mesh(source, "bones: a link index outside the character (rule: 0 to " +
                              std::to_string(nlinks - 2) + ")");
    }
    mesh.bones.push_back(b.get<int>() + 1);
  }
  for (const auto& m : h["inverse_bind"]) {
    if (!m.is_array() || m.size() != 16)
      refuse_mesh(source, "inverse_bind: a matrix of 16 numbers");
    double a[16];
    for (int k = 0; k < 16; ++k) {
      if (!m[k].is_number() || !std::isfinite(m[k].get<double>())) {
        refuse_mesh(source, "inverse_bind: a value is not a finite number");
      }
      a[k] = m[k].get<double>();
    }
    core::Transform X;
    for (int c = 0; c < 3; ++c) {
      for (int r = 0; r < 3; ++r) X.R(r, c) = a[4 * c + r];
    }
    X.p = core::Vector3(a[12], a[13], a[14]);
    mesh.inverse_bind.push_back(X);
  }
  if (h.contains("base_color") && h["base_color"].is_array() && h["base_color"].size() == 4) {
    for (int k = 0; k < 4; ++k) {
      if (h["base_color"][k].is_number()) mesh.base_color[k] = h["base_color"][k].get<float>();
    }
  }
  Reader in(bytes, 8 + std::size_t{length}, source);
  const std::vector<float> positions = in.take<float>(3 * n, "positions");
  check_finite(positions, source, "positions");
  for (std::size_t v = 0; v < n; ++v) {
    mesh.positions.emplace_back(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
  }
  if (h["normals"].get<bool>()) {
    const std::vector<float> normals = in.take<float>(3 * n, "normals");
    check_finite(normals, source, "normals");
    for (std::size_t v = 0; v < n; ++v) {
      mesh.normals.emplace_back(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]);
    }
  }
  const std::vector<std::uint32_t> indices = in.take<std::uint32_t>(3 * t, "indices");
  for (std::size_t k = 0; k < t; ++k) {
    std::array<int, 3> tri;
    for (int c = 0; c < 3; ++c) {
      if (indices[3 * k + c] >= n)
        refuse_mesh(source, "indices: a vertex index beyond the vertices");
      tri[c] = static_cast<int>(indices[3 * k + c]);
    }
    mesh.triangles.push_back(tri);
  }
  const std::vector<std::uint16_t> joints = in.take<std::uint16_t>(4 * n, "joints");
  const std::vector<float> weights = in.take<float>(4 * n, "weights");
  check_finite(weights, source, "weights");
  for (std::size_t v = 0; v < n; ++v) {
    std::array<int, 4> j;
    std::array<float, 4> w;
    for (int c = 0; c < 4; ++c) {
      j[c] = joints[4 * v + c];
      w[c] = weights[4 * v + c];
      if (static_cast<std::size_t>(j[c]) >= mesh.bones.size()) {
        if (w[c] != 0) refuse_mesh(source, "joints: a bone index beyond the bones");
        j[c] = 0;  // an unused slot
      }
    }
    mesh.joints.push_back(j);
    mesh.weights.push_back(w);
  }
  read_materials(h, in, source, mesh);
  return mesh;
}

}  // namespace server
