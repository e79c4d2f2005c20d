// The GL half of a thumbnail: one process-wide OSMesa context (GL 3.3 core, llvmpipe) behind a
// mutex, its two programs (figure, ground), buffers and multisampled framebuffers, created on
// first use and reused. thumbnail_renderer_stats() and release_thumbnail_renderer() are declared
// in server/thumbnail.hpp. docs: ../shared/reference/platform.md §3.
#pragma once

#include <cstdint>
#include <vector>

#include "server/thumbnail_scene.hpp"

namespace server {

/// Draws the scene and returns its pixels: scene.size² RGB triples, rows top to bottom.
/// Safe to call from any thread; the GL part is serialized.
/// @throws std::runtime_error when OSMesa cannot create a context, a framebuffer is incomplete,
///         a shader does not compile or GL reports an error
std::vector<std::uint8_t> draw_thumbnail_scene(const ThumbnailScene& scene);

}  // namespace server
