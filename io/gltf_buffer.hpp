// The binary side of the glTF writer (io/gltf.hpp): the buffer with its views and accessors,
// and the two containers for it (a base64 data URI in .gltf, the BIN chunk of a .glb).
// Internal to io/.
#pragma once

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace io::gltf_detail {

using Json = nlohmann::ordered_json;

// glTF enumerations (Specification §5: accessor.componentType, bufferView.target)
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;
constexpr int kFloat = 5126;
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;

/// Buffer 0 of the document: views aligned to 4 bytes, accessors with exact bounds.
class BufferBuilder {
 public:
  /// Appends a view (padded so the next one starts on a 4-byte boundary); returns its index.
  /// @param target  bufferView.target, or 0 for none
  int add_view(const void* bytes, std::size_t size, int target);

  /// A float accessor of values.size() / ncomp elements of `ncomp` components (`type`, e.g.
  /// "VEC3"); with `bounds`, min and max equal to the float values. Returns its index.
  int add_floats(
      const std::vector<float>& values, int ncomp, const char* type, bool bounds, int target);

  /// An integer accessor of `count` elements (unsigned short or int). Returns its index.
  template <typename T>
  int add_integers(const std::vector<T>& values,
                   int component_type,
                   const char* type,
                   std::size_t count,
                   int target) {
    const int view = add_view(values.data(), values.size() * sizeof(T), target);
    accessors_.push_back({{"bufferView", view},
                          {"componentType", component_type},
                          {"count", count},
                          {"type", type}});
    return static_cast<int>(accessors_.size()) - 1;
  }

  /// Triangle indices as unsigned short when `nverts` fit, else unsigned int.
  int add_indices(const std::vector<std::uint32_t>& idx, std::size_t nverts);

  const std::vector<std::uint8_t>& data() const { return data_; }
  Json& views() { return views_; }
  Json& accessors() { return accessors_; }

 private:
  std::vector<std::uint8_t> data_;
  Json views_ = Json::array();
  Json accessors_ = Json::array();
};

/// Standard base64 (RFC 4648 §4) with '=' padding.
std::string base64(const std::vector<std::uint8_t>& in);

/// A GLB (Specification §4.4): 12-byte header, the JSON chunk padded with spaces, the BIN chunk
/// padded with zeros, all 4-byte aligned.
/// @throws std::invalid_argument when it would exceed 4 GiB
std::vector<std::uint8_t> glb_container(std::string json, const std::vector<std::uint8_t>& bin);

}  // namespace io::gltf_detail
