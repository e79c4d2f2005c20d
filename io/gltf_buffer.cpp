#include "io/gltf_buffer.hpp"

#include <algorithm>
#include <limits>

namespace io::gltf_detail {

int BufferBuilder::add_view(const void* bytes, std::size_t size, int target) {
  std::vector<unsigned char>& data = doc_.buffers[0].data;
  tinygltf::BufferView v;
  v.buffer = 0;
  v.byteOffset = data.size();
  v.byteLength = size;
  v.target = target;
  const auto* p = static_cast<const unsigned char*>(bytes);
  data.insert(data.end(), p, p + size);
  data.resize((data.size() + 3) & ~std::size_t{3}, 0);
  doc_.bufferViews.push_back(std::move(v));
  return static_cast<int>(doc_.bufferViews.size()) - 1;
}

int BufferBuilder::add_floats(
    const std::vector<float>& values, int ncomp, int type, bool bounds, int target) {
  tinygltf::Accessor a;
  a.count = values.size() / static_cast<std::size_t>(ncomp);
  a.bufferView = add_view(values.data(), values.size() * sizeof(float), target);
  a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  a.type = type;
  if (bounds) {
    std::vector<float> lo(ncomp, std::numeric_limits<float>::infinity());
    std::vector<float> hi(ncomp, -std::numeric_limits<float>::infinity());
    for (std::size_t k = 0; k < a.count; ++k) {
      for (int c = 0; c < ncomp; ++c) {
        lo[c] = std::min(lo[c], values[k * ncomp + c]);
        hi[c] = std::max(hi[c], values[k * ncomp + c]);
      }
    }
    // the float values exactly, promoted to double, so the validator finds them equal
    a.minValues.assign(lo.begin(), lo.end());
    a.maxValues.assign(hi.begin(), hi.end());
  }
  doc_.accessors.push_back(std::move(a));
  return static_cast<int>(doc_.accessors.size()) - 1;
}

int BufferBuilder::add_indices(const std::vector<std::uint32_t>& idx, std::size_t nverts) {
  if (nverts <= 65535) {
    std::vector<std::uint16_t> s(idx.begin(), idx.end());
    return add_integers(s, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR, s.size(),
                        TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  }
  return add_integers(idx, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, idx.size(),
                      TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
}

}  // namespace io::gltf_detail
