#include "server/mesh_binary.hpp"

#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>

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
  const nlohmann::json header{
      {"name", mesh.name},
      {"vertices", n},
      {"triangles", mesh.triangles.size()},
      {"normals", normals},
      {"bones", bones},
      {"inverse_bind", inverse_bind},
      {"base_color",
       {mesh.base_color[0], mesh.base_color[1], mesh.base_color[2], mesh.base_color[3]}}};
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
  return out;
}

}  // namespace server
