// Thumbnails: a character in a pose, rendered off-screen with OSMesa (software GL, llvmpipe) and
// returned as PNG bytes. docs: ../shared/reference/platform.md §3.
//
// What is drawn: every primitive shape of every link (capsules, spheres, boxes, cylinders; a
// link's visual shapes, or its collision shapes when it has no visual primitive) as lit,
// depth-tested, 4× multisampled meshes; links with no primitive at all (mesh-only URDFs) get a
// bone from their parent instead. Given a core::SkinnedMesh, the skin is drawn instead of the
// shapes, deformed on the CPU by linear blend skinning. Links left of the figure's centre (+X at
// the neutral configuration) are tinted cool and links right of it warm, so a pose reads at a
// glance. Behind: a flat neutral background, and on the ground (y = 0, or the figure's lowest
// point when it reaches below 0) a soft shadow disc and a grid that fades out around the figure.
//
// The camera: a 3/4 front view (35° to the figure's left of +Z, 12° above), perspective with a
// 30° field of view, aimed and distanced so that core::world_bounds of the pose (with the skin's
// vertices) fills 80 % of the image height (at most 90 % of its width), centred.
//
// Threads: render_thumbnail may be called from any number of threads at once. The GL part of a
// render (upload, draw, read back; about a millisecond at 256 px) runs on one process-wide OSMesa
// context behind a mutex, made current on the calling thread for the duration and released
// afterwards; everything else (validation, kinematics, skinning, camera, PNG encoding) runs on
// the calling thread in parallel. One context, not one per thread: Mesa 22's OSMesa keeps the
// framebuffers of all contexts in one unlocked global list and hands two contexts of equal size
// and format the same framebuffer, so per-thread contexts are not safe. The context, its
// programs and buffers are created on first use and reused; a render creates no GL object that
// outlives it (the sized framebuffers are replaced, not added to, when the size changes), which
// thumbnail_renderer_stats() lets a test check. release_thumbnail_renderer() frees them all.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/model.hpp"
#include "core/skin.hpp"

namespace server {

/// Accepted thumbnail sizes (pixels per side).
constexpr int kThumbnailMinSize = 16;
constexpr int kThumbnailMaxSize = 1024;
/// Default byte cap of a ThumbnailCache: PNG bytes plus keys.
constexpr std::size_t kDefaultThumbnailCacheBytes = std::size_t{32} << 20;

class ThumbnailCache;

enum class ThumbnailGround {
  kGridAndShadow,  // a fading grid and a soft shadow disc under the figure (default)
  kShadow,         // the shadow disc only
  kNone,           // background only: every pixel that is not the figure has the background colour
};

struct ThumbnailOptions {
  int size = 256;  // S × S pixels, in [kThumbnailMinSize, kThumbnailMaxSize]
  ThumbnailGround ground = ThumbnailGround::kGridAndShadow;
  std::array<std::uint8_t, 3> background{0xE4, 0xE6, 0xEA};  // sRGB, a light neutral grey
  /// When set, a render with an equal key (model content, q's bytes, skin content, the options
  /// above) is answered from the cache, and a new render is stored in it. Not owned.
  ThumbnailCache* cache = nullptr;
};

/// The character in configuration q as an RGB PNG of options.size × options.size pixels.
/// The frame of a clip is the caller's business: pass that frame's configuration.
/// @param q     configuration (nq), finite; quaternions are renormalized (a zero one is refused)
/// @param skin  optional skinned mesh bound to `model`'s links: drawn instead of the shapes
/// @throws std::invalid_argument naming the field when the size is out of range, q does not fit
///         the model, or the skin is inconsistent (sizes, indices, non-finite values)
/// @throws std::runtime_error when OSMesa cannot create a context or GL reports an error
std::vector<std::uint8_t> render_thumbnail(const core::Model& model,
                                           const Eigen::VectorXd& q,
                                           const ThumbnailOptions& options,
                                           const core::SkinnedMesh* skin = nullptr);

struct ThumbnailCacheStats {
  std::size_t entries = 0;
  std::size_t bytes = 0;  // PNG bytes plus key bytes of the entries held
  std::size_t byte_cap = 0;
  std::uint64_t hits = 0;
  std::uint64_t misses = 0;
  std::uint64_t evictions = 0;
};

/// A least-recently-used store of rendered PNGs, bounded by bytes (PNG plus key). Internally
/// locked: one cache may serve any number of threads. Two threads missing the same key at once
/// both render it; the second store replaces the first.
class ThumbnailCache {
 public:
  explicit ThumbnailCache(std::size_t byte_cap = kDefaultThumbnailCacheBytes);
  ThumbnailCache(const ThumbnailCache&) = delete;
  ThumbnailCache& operator=(const ThumbnailCache&) = delete;

  /// The PNG stored under `key` (and it becomes the most recently used), or nullptr.
  std::shared_ptr<const std::vector<std::uint8_t>> find(const std::string& key);
  /// Stores `png` under `key`, evicting least recently used entries to stay within the cap. An
  /// entry larger than the cap on its own is not stored.
  void insert(const std::string& key, std::shared_ptr<const std::vector<std::uint8_t>> png);
  void clear();
  ThumbnailCacheStats stats() const;

 private:
  struct Entry {
    std::string key;
    std::shared_ptr<const std::vector<std::uint8_t>> png;
    std::size_t bytes = 0;
  };
  void evict_to(std::size_t cap);  // requires mutex_

  mutable std::mutex mutex_;
  std::list<Entry> lru_;  // front: most recently used
  std::unordered_map<std::string, std::list<Entry>::iterator> index_;
  ThumbnailCacheStats stats_;
};

/// The cache key of a render: a 64-bit digest of the model's drawn content (topology, joint
/// types, placements, axes, shapes) and of the skin, q's exact bytes, and the options.
std::string thumbnail_cache_key(const core::Model& model,
                                const Eigen::VectorXd& q,
                                const ThumbnailOptions& options,
                                const core::SkinnedMesh* skin = nullptr);

/// State of the process-wide renderer, for diagnostics and tests.
struct ThumbnailRendererStats {
  bool context_alive = false;
  int gl_objects = 0;         // GL objects alive in the context (glIs* on every name it created)
  std::uint64_t renders = 0;  // renders that reached the GL since the context was created
  int samples = 0;            // multisampling used
  std::string gl_version;     // e.g. "4.5 (Core Profile) Mesa 22.3.6"
  std::string gl_renderer;    // e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
};
ThumbnailRendererStats thumbnail_renderer_stats();

/// Destroys the renderer's GL objects and its OSMesa context (waiting for a render in progress);
/// the next render creates them again.
void release_thumbnail_renderer();

}  // namespace server
