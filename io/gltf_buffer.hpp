// The binary side of the glTF writer (io/gltf.hpp): buffer 0 of a tinygltf::Model with its
// views and accessors. Internal to io/.
#pragma once

#include <tiny_gltf.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace io::gltf_detail {

/// Buffer 0 of the document: views aligned to 4 bytes, accessors with exact bounds.
class BufferBuilder {
 public:
  explicit BufferBuilder(tinygltf::Model& doc) : doc_(doc) { doc_.buffers.resize(1); }

  /// Appends a view (padded so the next one starts on a 4-byte boundary); returns its index.
  /// @param target  bufferView.target, or 0 for none
  int add_view(const void* bytes, std::size_t size, int target);

  /// A float accessor of values.size() / ncomp elements of `ncomp` components (`type`, e.g.
  /// TINYGLTF_TYPE_VEC3); with `bounds`, min and max equal to the float values.
  int add_floats(const std::vector<float>& values, int ncomp, int type, bool bounds, int target);

  /// An integer accessor of `count` elements (unsigned short or int). Returns its index.
  template <typename T>
  int add_integers(
      const std::vector<T>& values, int component_type, int type, std::size_t count, int target) {
    tinygltf::Accessor a;
    a.bufferView = add_view(values.data(), values.size() * sizeof(T), target);
    a.componentType = component_type;
    a.count = count;
    a.type = type;
    doc_.accessors.push_back(std::move(a));
    return static_cast<int>(doc_.accessors.size()) - 1;
  }

  /// Triangle indices as unsigned short when `nverts` fit, else unsigned int.
  int add_indices(const std::vector<std::uint32_t>& idx, std::size_t nverts);

 private:
  tinygltf::Model& doc_;
};

}  // namespace io::gltf_detail
