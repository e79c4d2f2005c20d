// `pindrag convert IN OUT`: BVH ↔ glTF/GLB, and skinned characters (glTF, GLB, FBX, DAE) to glTF
// or BVH, by the extensions of the two paths.
#include <cmath>
#include <iostream>
#include <optional>

#include "cli/clip_file.hpp"
#include "cli/commands.hpp"
#include "cli/progress_bar.hpp"
#include "io/bvh.hpp"

namespace cli {

namespace {

struct ConvertArgs {
  std::string in, out, order, units;
  std::optional<double> scale, fps;
  bool quiet = false;
};

void convert(const ConvertArgs& a) {
  const auto in_format = clip_format(a.in);
  const auto out_format = clip_format(a.out);
  if (!out_format || !writable(*out_format)) {
    throw std::invalid_argument("OUT: " + a.out +
                                " (rule: the extension must be .bvh, .gltf or .glb)");
  }
  const bool bvh_in = in_format == ClipFormat::kBvh, bvh_out = out_format == ClipFormat::kBvh;
  // "source" (or no option) keeps a BVH input's unit and per-joint orders (io/bvh_writer.hpp)
  ClipWriteOptions wo;
  if (!a.order.empty()) {
    if (!bvh_out) throw std::invalid_argument("--order: applies to a BVH output only");
    wo.bvh_order = io::parse_bvh_order(a.order, "--order");
  }
  if (!a.units.empty()) {
    if (!bvh_out) throw std::invalid_argument("--units: applies to a BVH output only");
    if (a.scale && !bvh_in) {
      throw std::invalid_argument("--units: not with --scale, which sets the BVH output's unit");
    }
    wo.bvh_scale = io::parse_bvh_units(a.units, "--units");
  }
  if (a.scale && !(std::isfinite(*a.scale) && *a.scale > 0)) {
    throw std::invalid_argument("--scale: must be a positive number (metres per BVH file unit)");
  }
  if (a.scale && !bvh_in && !bvh_out)
    throw std::invalid_argument("--scale: applies to BVH files only");

  ProgressBar bar("converting", !a.quiet);
  // --scale is the unit of the BVH side: the input's when it is BVH (the output then keeps that
  // unit), else the output's
  ClipReadOptions ro;
  if (bvh_in) ro.bvh_scale = a.scale;
  ro.fps = a.fps;
  ro.progress = [&bar](double f) { bar.update(0.5 * f); };
  const ClipFile clip = read_clip_file(a.in, ro);

  if (bvh_out && !bvh_in && a.scale) wo.bvh_scale = a.scale;
  wo.progress = [&bar](double f) { bar.update(0.5 + 0.5 * f); };
  write_clip_file(a.out, clip, clip.clip, wo);
  bar.update(1.0);
  bar.finish();
  for (const std::string& w : clip.warnings) std::cerr << "warning: " << w << "\n";
  std::cerr << "pindrag convert: " << a.out << ": " << clip.clip.size() << " frames at "
            << 1.0 / clip.clip.frame_time << " fps, " << clip.model->nlinks() << " links\n";
}

}  // namespace

void add_convert_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "convert",
      "convert an animation: BVH <-> glTF/GLB, skinned glTF/GLB/FBX/DAE -> glTF/GLB/BVH");
  auto args = std::make_shared<ConvertArgs>();
  cmd->add_option("IN", args->in, "input clip (.bvh, .gltf, .glb, .fbx, .dae)")->required();
  cmd->add_option("OUT", args->out, "output clip (.bvh, .gltf, .glb)")->required();
  cmd->add_option("--order", args->order,
                  "BVH output rotation order for every joint: XYZ, XZY, YXZ, YZX, ZXY, ZYX, or "
                  "source (the default): each joint's order in a BVH input, else ZXY");
  cmd->add_option("--units", args->units,
                  "BVH output unit: m, cm, or source (the default): the unit of a BVH input, "
                  "else metres (or --scale)");
  cmd->add_option("--scale", args->scale,
                  "metres per BVH file unit: of the input when it is "
                  "BVH (default: chosen from the skeleton's size; the "
                  "output keeps it unless --units), else of the BVH output (default 1)");
  cmd->add_option("--fps", args->fps, "resample the clip at this frame rate");
  cmd->add_flag("--quiet", args->quiet, "no progress bar");
  cmd->callback([args] {
    try {
      convert(*args);
    } catch (
        const std::exception& e) {  // ModelError, invalid_argument, system_error: all name the file
      std::cerr << "pindrag convert: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace cli
