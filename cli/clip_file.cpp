#include "cli/clip_file.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include "core/configuration.hpp"
#include "core/model_builder.hpp"
#include "io/assimp_import.hpp"
#include "io/gltf.hpp"

namespace cli {

namespace {

// most frames a resampled clip may have (as the BVH reader's limit)
[[noreturn]] void refuse(const std::string& message) { throw core::ModelError({message}); }

constexpr double kMaxResampledFrames = static_cast<double>(io::kMaxBvhFrames);

}  // namespace

std::string lower_extension(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::optional<ClipFormat> clip_format(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".bvh") return ClipFormat::kBvh;
  if (ext == ".gltf") return ClipFormat::kGltf;
  if (ext == ".glb") return ClipFormat::kGlb;
  if (ext == ".fbx") return ClipFormat::kFbx;
  if (ext == ".dae") return ClipFormat::kDae;
  return std::nullopt;
}

bool writable(ClipFormat f) {
  return f == ClipFormat::kBvh || f == ClipFormat::kGltf || f == ClipFormat::kGlb;
}

core::Clip resample(const core::Model& model, const core::Clip& clip, double fps) {
  if (!(std::isfinite(fps) && fps > 0 && fps <= 1000)) {
    throw std::invalid_argument("--fps: must be a number in (0, 1000]");
  }
  core::Clip out;
  out.frame_time = 1.0 / fps;
  if (clip.empty()) return out;
  // whole frames of the new rate within the duration (a thousandth of a frame of slack for
  // durations that are whole numbers of frames up to rounding)
  const double last = std::floor(clip.duration() * fps + 1e-3);
  if (last + 1 > kMaxResampledFrames) {
    throw std::invalid_argument("--fps: resampling at " + std::to_string(fps) +
                                " fps would make more than " + std::to_string(io::kMaxBvhFrames) +
                                " frames");
  }
  const int n = static_cast<int>(last) + 1;
  out.frames.resize(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    core::sample(model, clip, std::min(k * out.frame_time, clip.duration()), out.frames[k]);
  }
  return out;
}

ClipFile read_clip_file(const std::string& path, const ClipReadOptions& options) {
  const auto format = clip_format(path);
  if (!format) {
    refuse(path +
           ": unknown clip format (rule: the extension must be .bvh, .gltf, .glb, .fbx "
           "or .dae)");
  }
  if (options.fps && !(std::isfinite(*options.fps) && *options.fps > 0 && *options.fps <= 1000)) {
    refuse(path + ": --fps must be a number in (0, 1000]");
  }
  ClipFile out;
  if (*format == ClipFormat::kBvh) {
    io::BvhImportOptions o;
    o.scale = options.bvh_scale;
    o.progress = options.progress;
    io::BvhImport imp = io::load_bvh_file(path, o);
    out.model = imp.model;
    out.clip = std::move(imp.clip);
    out.bvh_layout = std::move(imp.layout);
    out.unit = imp.unit;
    out.warnings = std::move(imp.warnings);
    if (options.fps) out.clip = resample(*out.model, out.clip, *options.fps);
    return out;
  }
  io::ImportOptions o;
  if (options.fps) o.frame_rate = *options.fps;
  if (options.progress) options.progress(0.0);
  io::SkinnedImport imp = io::import_skinned_file(path, {}, o);
  if (options.progress) options.progress(1.0);
  out.model = imp.model;
  out.skin = std::make_shared<const core::SkinnedMesh>(std::move(imp.mesh));
  out.warnings = std::move(imp.warnings);
  out.clips_in_file = static_cast<int>(imp.clips.size());
  if (imp.clips.empty()) {
    out.clip.frame_time = 1.0 / o.frame_rate;
    out.clip.frames.push_back(core::neutral_configuration(*out.model));
    out.warnings.push_back(path + ": no animation; the clip is the bind pose as one frame");
  } else {
    out.clip_name = imp.clips[0].name;
    out.clip = std::move(imp.clips[0].clip);
    if (imp.clips.size() > 1) {
      out.warnings.push_back(path + ": " + std::to_string(imp.clips.size()) +
                             " animations; the first ('" + out.clip_name + "') is used");
    }
  }
  return out;
}

void write_clip_file(const std::string& path,
                     const ClipFile& source,
                     const core::Clip& clip,
                     const ClipWriteOptions& options) {
  const auto format = clip_format(path);
  if (!format || !writable(*format)) {
    throw std::invalid_argument(path +
                                ": cannot write this format (rule: the output extension "
                                "must be .bvh, .gltf or .glb)");
  }
  if (*format == ClipFormat::kBvh) {
    io::BvhExportOptions o;
    o.rotation_order = options.bvh_order;
    o.scale = options.bvh_scale;
    o.layout = source.bvh_layout ? &*source.bvh_layout : nullptr;
    o.progress = options.progress;
    io::save_bvh_file(*source.model, clip, path, o);
    return;
  }
  if (options.bvh_order || options.bvh_scale) {
    throw std::invalid_argument(path + ": --order and --scale apply to BVH files only");
  }
  const bool skinned = source.skin && !source.skin->empty();
  io::GltfExportOptions o;
  o.stick_figure = !skinned && options.stick_figure;
  o.shape_mesh = !skinned && !options.stick_figure && options.shape_mesh;
  if (options.progress) options.progress(0.0);
  io::save_gltf_file(path, *source.model, &clip, skinned ? source.skin.get() : nullptr, o);
  if (options.progress) options.progress(1.0);
}

}  // namespace cli
