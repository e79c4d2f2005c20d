#include "io/gltf_buffer.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace io::gltf_detail {

namespace {

// GLB container (Specification §4.4)
constexpr std::uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr std::uint32_t kGlbVersion = 2;
constexpr std::uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942;   // "BIN\0"

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
}

}  // namespace

int BufferBuilder::add_view(const void* bytes, std::size_t size, int target) {
  const std::size_t offset = data_.size();
  data_.resize(offset + size);
  if (size > 0) std::memcpy(data_.data() + offset, bytes, size);
  data_.resize((data_.size() + 3) & ~std::size_t{3}, 0);
  Json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}};
  if (target != 0) v["target"] = target;
  views_.push_back(std::move(v));
  return static_cast<int>(views_.size()) - 1;
}

int BufferBuilder::add_floats(
    const std::vector<float>& values, int ncomp, const char* type, bool bounds, int target) {
  const std::size_t count = values.size() / static_cast<std::size_t>(ncomp);
  const int view = add_view(values.data(), values.size() * sizeof(float), target);
  Json a = {{"bufferView", view}, {"componentType", kFloat}, {"count", count}, {"type", type}};
  if (bounds) {
    std::vector<float> lo(ncomp, std::numeric_limits<float>::infinity());
    std::vector<float> hi(ncomp, -std::numeric_limits<float>::infinity());
    for (std::size_t k = 0; k < count; ++k) {
      for (int c = 0; c < ncomp; ++c) {
        lo[c] = std::min(lo[c], values[k * ncomp + c]);
        hi[c] = std::max(hi[c], values[k * ncomp + c]);
      }
    }
    // the float values exactly, promoted to double, so the validator finds them equal
    Json jlo = Json::array(), jhi = Json::array();
    for (int c = 0; c < ncomp; ++c) {
      jlo.push_back(static_cast<double>(lo[c]));
      jhi.push_back(static_cast<double>(hi[c]));
    }
    a["min"] = std::move(jlo);
    a["max"] = std::move(jhi);
  }
  accessors_.push_back(std::move(a));
  return static_cast<int>(accessors_.size()) - 1;
}

int BufferBuilder::add_indices(const std::vector<std::uint32_t>& idx, std::size_t nverts) {
  if (nverts <= 65535) {
    std::vector<std::uint16_t> s(idx.begin(), idx.end());
    return add_integers(s, kUnsignedShort, "SCALAR", s.size(), kElementArrayBuffer);
  }
  return add_integers(idx, kUnsignedInt, "SCALAR", idx.size(), kElementArrayBuffer);
}

std::string base64(const std::vector<std::uint8_t>& in) {
  static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const std::uint32_t v = (in[i] << 16) | (in[i + 1] << 8) | in[i + 2];
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += alphabet[(v >> 6) & 63];
    out += alphabet[v & 63];
  }
  if (i + 1 == in.size()) {
    const std::uint32_t v = in[i] << 16;
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == in.size()) {
    const std::uint32_t v = (in[i] << 16) | (in[i + 1] << 8);
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += alphabet[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

std::vector<std::uint8_t> glb_container(std::string json, const std::vector<std::uint8_t>& bin) {
  json.resize((json.size() + 3) & ~std::size_t{3}, ' ');
  const std::size_t bin_size = (bin.size() + 3) & ~std::size_t{3};
  const std::size_t total = 12 + 8 + json.size() + 8 + bin_size;
  if (total > std::numeric_limits<std::uint32_t>::max()) {
    throw std::invalid_argument("glTF export: the GLB would exceed 4 GiB");
  }
  std::vector<std::uint8_t> out;
  out.reserve(total);
  put_u32(out, kGlbMagic);
  put_u32(out, kGlbVersion);
  put_u32(out, static_cast<std::uint32_t>(total));
  put_u32(out, static_cast<std::uint32_t>(json.size()));
  put_u32(out, kChunkJson);
  out.insert(out.end(), json.begin(), json.end());
  put_u32(out, static_cast<std::uint32_t>(bin_size));
  put_u32(out, kChunkBin);
  out.insert(out.end(), bin.begin(), bin.end());
  out.resize(total, 0);
  return out;
}

}  // namespace io::gltf_detail
