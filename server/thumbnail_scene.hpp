// The CPU half of a thumbnail: input checks, the posed figure as one triangle mesh (shapes or the
// skinned mesh), the camera that frames it and the ground under it. Runs on the calling thread;
// server/thumbnail_renderer.hpp draws the result. Design: server/thumbnail.hpp.
#pragma once

#include <Eigen/Core>
#include <array>

#include "core/model.hpp"
#include "core/skin.hpp"
#include "io/shape_mesh.hpp"
#include "server/thumbnail.hpp"

namespace server {

/// Everything the renderer needs, in the render frame F: the world translated so that the centre
/// of the figure's bounds is the origin (keeps float coordinates small wherever the figure is).
struct ThumbnailScene {
  int size = 256;
  io::TriangleMesh figure;
  Eigen::Matrix4f view_projection = Eigen::Matrix4f::Identity();  // F → clip space
  Eigen::Vector3f eye_F = Eigen::Vector3f::Zero();
  std::array<float, 3> background{};  // sRGB in [0, 1]
  // ground: a square of half side fade_radius centred under the figure, on y = ground_y
  bool draw_shadow = false;
  bool draw_grid = false;
  float ground_y = 0;
  float fade_radius = 1;    // the grid fades out towards this distance from the figure's centre
  float shadow_radius = 0;  // the shadow disc's soft edge reaches out to about this distance
  float grid_step = 0.25f;  // spacing of the grid lines
};

/// Field of view, viewing direction and framing of the camera (server/thumbnail.hpp).
constexpr double kCameraFovDegrees = 30;
constexpr double kCameraAzimuthDegrees = 35;  // towards +X (the figure's left) from +Z
constexpr double kCameraElevationDegrees = 12;
constexpr double kFillHeight = 0.8;  // fraction of the image height the bounds fill
constexpr double kMaxFillWidth = 0.9;

/// options.size within [kThumbnailMinSize, kThumbnailMaxSize].
/// @throws std::invalid_argument naming options.size
void check_thumbnail_size(int size);

/// q with its quaternions renormalized.
/// @throws std::invalid_argument naming q (its size, the entry and joint that are not finite, or
///         the joint whose quaternion is zero)
Eigen::VectorXd checked_configuration(const core::Model& model, const Eigen::VectorXd& q);

/// @throws std::invalid_argument naming the skin's field and index when its sizes disagree, an
///         index is out of range, a value is not finite or a vertex's weights do not sum to > 0
void check_skin(const core::Model& model, const core::SkinnedMesh& skin);

/// The scene of a checked configuration (checked_configuration) and skin (check_skin; an empty
/// skin counts as none).
/// @throws std::invalid_argument when the model has no links
ThumbnailScene build_thumbnail_scene(const core::Model& model,
                                     const Eigen::VectorXd& q,
                                     const ThumbnailOptions& options,
                                     const core::SkinnedMesh* skin);

}  // namespace server
