// pindrag thumbnail: a character, or one frame of a clip, rendered to PNG (server/thumbnail.hpp).
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>

#include "cli/commands.hpp"
#include "core/configuration.hpp"
#include "io/assimp_import.hpp"
#include "io/bundled_characters.hpp"
#include "io/bvh.hpp"
#include "server/thumbnail.hpp"

namespace cli {

namespace {

// what a file gives to draw: a model, its motion (may be empty) and perhaps a skin
struct Subject {
  std::shared_ptr<const core::Model> model;
  core::Clip clip;
  std::optional<core::SkinnedMesh> skin;
};

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

Subject load_subject(const std::string& file) {
  const std::string ext = lower_extension(file);
  Subject s;
  if (ext == ".bvh") {
    io::BvhImport bvh = io::load_bvh_file(file);
    s.model = bvh.model;
    s.clip = std::move(bvh.clip);
  } else if (ext == ".glb" || ext == ".gltf" || ext == ".fbx" || ext == ".dae") {
    io::SkinnedImport imported = io::import_skinned_file(file);
    s.model = imported.model;
    if (!imported.mesh.empty()) s.skin = std::move(imported.mesh);
    if (!imported.clips.empty()) s.clip = std::move(imported.clips.front().clip);
  } else {
    s.model = io::load_character(file).model;
  }
  return s;
}

// the configuration to draw: frame N of the clip, or the neutral one of a character
Eigen::VectorXd pick_frame(const Subject& s, const std::string& file, int frame, bool frame_given) {
  if (s.clip.empty()) {
    if (frame_given && frame != 0)
      throw std::invalid_argument("--frame " + std::to_string(frame) + ": " + file +
                                  " has no motion, only frame 0 (the neutral pose)");
    return core::neutral_configuration(*s.model);
  }
  if (frame < 0 || frame >= s.clip.size())
    throw std::invalid_argument("--frame " + std::to_string(frame) + ": " + file + " has " +
                                std::to_string(s.clip.size()) + " frames (0.." +
                                std::to_string(s.clip.size() - 1) + ")");
  return s.clip.frames[static_cast<std::size_t>(frame)];
}

void write_file(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (out)
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
  if (out) out.close();
  if (!out)
    throw std::runtime_error("-o " + path + ": cannot write (" + std::strerror(errno) + ")");
}

}  // namespace

void add_thumbnail_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "thumbnail",
      "render a character, or one frame of a clip, to a PNG (lit capsules, or the skinned mesh)");
  struct Arguments {
    std::string file, out;
    int frame = 0;
    int size = 256;
  };
  auto args = std::make_shared<Arguments>();
  cmd->add_option("FILE", args->file,
                  "character (.urdf, .json or a bundled name such as human48), BVH clip, or "
                  "skinned character (.glb, .gltf, .fbx, .dae)")
      ->required();
  cmd->add_option("-o,--output", args->out, "PNG file to write")->required();
  auto* frame_option = cmd->add_option("--frame", args->frame, "frame of the clip (from 0)");
  cmd->add_option("--size", args->size, "pixels per side")
      ->check(CLI::Range(server::kThumbnailMinSize, server::kThumbnailMaxSize));
  cmd->callback([args, frame_option] {
    try {
      const Subject subject = load_subject(args->file);
      const Eigen::VectorXd q =
          pick_frame(subject, args->file, args->frame, frame_option->count() > 0);
      server::ThumbnailOptions options;
      options.size = args->size;
      const std::vector<std::uint8_t> png = server::render_thumbnail(
          *subject.model, q, options, subject.skin ? &*subject.skin : nullptr);
      write_file(args->out, png);
      std::cout << "wrote " << args->out << " (" << args->size << " x " << args->size << " px, "
                << png.size() << " bytes)\n";
    } catch (const std::exception& e) {
      // ModelError (loaders), invalid_argument (frame, size, skin), runtime_error (GL, output)
      std::cerr << "pindrag thumbnail: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace cli
