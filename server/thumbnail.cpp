// render_thumbnail: checks, cache look-up, scene (calling thread), GL (serialized), PNG (calling
// thread), cache store; and the cache key's digest.
#include "server/thumbnail.hpp"

#include <cstring>
#include <type_traits>

#include "server/png_encode.hpp"
#include "server/thumbnail_renderer.hpp"
#include "server/thumbnail_scene.hpp"

namespace server {

namespace {

// A 64-bit digest over 8-byte words: per word, xor it in, multiply by the FNV-1a prime and fold
// the high bits down; at the end a murmur3-style avalanche.
// Not cryptographic: it tells renders apart, it does not defend against crafted collisions.
class Digest {
 public:
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::uint64_t word = 0;
    for (; n >= 8; n -= 8, p += 8) {
      std::memcpy(&word, p, 8);
      mix(word);
    }
    word = 0;
    std::memcpy(&word, p, n);
    mix(word ^ (std::uint64_t{n} << 56));
  }
  template <typename T>
  void value(const T& v) {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>);
    bytes(&v, sizeof v);
  }
  void text(const std::string& s) {
    value(s.size());
    bytes(s.data(), s.size());
  }
  template <typename Matrix>
  void matrix(const Matrix& m) {
    bytes(m.data(), sizeof(typename Matrix::Scalar) * m.size());
  }
  void transform(const core::Transform& X) {
    matrix(X.R);
    matrix(X.p);
  }
  template <typename T>
  void array_vector(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T> && std::has_unique_object_representations_v<T>);
    value(v.size());
    bytes(v.data(), v.size() * sizeof(T));
  }
  std::uint64_t result() const {
    // a final avalanche so that every input bit reaches every output bit
    std::uint64_t h = h_;
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    h ^= h >> 33;
    return h;
  }

 private:
  void mix(std::uint64_t word) {
    h_ ^= word;
    h_ *= 0x100000001b3ULL;
    h_ ^= h_ >> 29;
  }
  std::uint64_t h_ = 0xcbf29ce484222325ULL;
};

std::string hex(std::uint64_t v) {
  static const char* const kDigits = "0123456789abcdef";
  std::string s(16, '0');
  for (int i = 15; i >= 0; --i, v >>= 4) s[i] = kDigits[v & 15];
  return s;
}

void add_shapes(Digest& d, const std::vector<core::Geometry>& shapes) {
  d.value(shapes.size());
  for (const core::Geometry& g : shapes) {
    d.value(g.shape);
    d.transform(g.X_LinkShape);
    d.value(g.radius);
    d.value(g.length);
    d.matrix(g.size);
    d.text(g.mesh);
    d.matrix(g.scale);
  }
}

std::uint64_t model_digest(const core::Model& model) {
  Digest d;
  d.value(model.njoints);
  d.value(model.nq);
  for (int i = 0; i < model.njoints; ++i) {
    d.value(model.parent[i]);
    d.value(model.joint_type[i]);
    d.transform(model.X_PJ[i]);
    d.matrix(model.axis[i]);
    add_shapes(d, model.visual[i]);
    add_shapes(d, model.collision[i]);
  }
  return d.result();
}

std::uint64_t skin_digest(const core::SkinnedMesh& skin) {
  Digest d;
  d.value(skin.positions.size());
  for (const auto& p : skin.positions) d.matrix(p);
  d.value(skin.normals.size());
  for (const auto& n : skin.normals) d.matrix(n);
  d.array_vector(skin.triangles);
  d.array_vector(skin.joints);
  d.value(skin.weights.size());
  for (const auto& w : skin.weights) d.bytes(w.data(), sizeof w);
  d.array_vector(skin.bones);
  for (const auto& X : skin.inverse_bind) d.transform(X);
  d.matrix(skin.base_color);
  return d.result();
}

}  // namespace

std::string thumbnail_cache_key(const core::Model& model,
                                const Eigen::VectorXd& q,
                                const ThumbnailOptions& options,
                                const core::SkinnedMesh* skin) {
  // model and skin digests, options in clear, then q's exact bytes in hex
  std::string key = "thumb1/m" + hex(model_digest(model));
  key += (skin != nullptr && !skin->empty()) ? "/s" + hex(skin_digest(*skin)) : "/s-";
  key += "/" + std::to_string(options.size) + "/g" +
         std::to_string(static_cast<int>(options.ground)) + "/b";
  for (std::uint8_t c : options.background) key += hex(c).substr(14);
  key += "/q";
  const auto* bytes = reinterpret_cast<const unsigned char*>(q.data());
  for (std::size_t i = 0; i < sizeof(double) * static_cast<std::size_t>(q.size()); ++i)
    key += hex(bytes[i]).substr(14);
  return key;
}

std::vector<std::uint8_t> render_thumbnail(const core::Model& model,
                                           const Eigen::VectorXd& q,
                                           const ThumbnailOptions& options,
                                           const core::SkinnedMesh* skin) {
  check_thumbnail_size(options.size);
  const Eigen::VectorXd q_unit = checked_configuration(model, q);
  if (skin != nullptr) check_skin(model, *skin);

  std::string key;
  if (options.cache != nullptr) {
    key = thumbnail_cache_key(model, q, options, skin);
    if (auto hit = options.cache->find(key)) return *hit;
  }
  const ThumbnailScene scene = build_thumbnail_scene(model, q_unit, options, skin);
  const std::vector<std::uint8_t> rgb = draw_thumbnail_scene(scene);
  std::vector<std::uint8_t> png = encode_png_rgb(rgb, options.size, options.size);
  if (options.cache != nullptr)
    options.cache->insert(key, std::make_shared<const std::vector<std::uint8_t>>(png));
  return png;
}

}  // namespace server
