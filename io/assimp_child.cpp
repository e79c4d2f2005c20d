#include "io/assimp_child.hpp"

#include <assimp/DefaultIOSystem.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/IOStream.hpp>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "io/assimp_animation.hpp"
#include "io/assimp_mesh.hpp"
#include "io/assimp_reply.hpp"
#include "io/assimp_rigid.hpp"
#include "io/assimp_scene.hpp"
#include "io/assimp_skeleton.hpp"
#include "io/sandbox.hpp"

namespace io::assimp_detail {

namespace {

namespace fs = std::filesystem;

// Reads only files inside the folder of the imported file (a .gltf's buffers); refuses the rest.
class FolderIOSystem : public Assimp::DefaultIOSystem {
 public:
  explicit FolderIOSystem(fs::path folder) : folder_(std::move(folder)) {}
  bool Exists(const char* file) const override {
    return inside(file) && Assimp::DefaultIOSystem::Exists(file);
  }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (!inside(file) || std::strchr(mode, 'w') != nullptr || std::strchr(mode, 'a') != nullptr) {
      return nullptr;
    }
    return Assimp::DefaultIOSystem::Open(file, mode);
  }

 private:
  bool inside(const char* file) const {
    std::error_code ec;
    const fs::path p = fs::weakly_canonical(fs::path(file), ec);
    if (ec) return false;
    const auto rel = p.lexically_relative(folder_);
    return !rel.empty() && *rel.begin() != ".." && !rel.is_absolute();
  }
  fs::path folder_;
};

// the largest image file a material may name that is read from beside the file
constexpr std::uintmax_t kMaxImageFile = std::uintmax_t{64} << 20;

// Image files a material names, read from the folder of `path` (and below) only: the name as
// written, else its last component (a path from the machine the file was made on).
ImageFileReader image_reader_beside(const std::string& path) {
  return [folder = fs::weakly_canonical(fs::path(path)).parent_path()](const std::string& name) {
    FolderIOSystem io(folder);
    std::string normalized = name;
    std::replace(normalized.begin(), normalized.end(), '\\', '/');
    for (const fs::path& candidate :
         {folder / fs::path(normalized), folder / fs::path(normalized).filename()}) {
      const std::string file = candidate.string();
      if (!io.Exists(file.c_str())) continue;
      Assimp::IOStream* stream = io.Open(file.c_str(), "rb");
      if (stream == nullptr) continue;
      std::string bytes;
      if (stream->FileSize() <= kMaxImageFile) {
        bytes.resize(stream->FileSize());
        if (stream->Read(bytes.data(), 1, bytes.size()) != bytes.size()) bytes.clear();
      }
      io.Close(stream);
      if (!bytes.empty()) return bytes;
    }
    return std::string();
  };
}

}  // namespace

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

SkinnedImport convert_scene(const aiScene& scene,
                            const std::string& path,
                            const ImportOptions& options) {
  Warnings warnings(fs::path(path).filename().string());
  const SceneNodes nodes = index_nodes(scene);
  const WorldAxes world = world_axes(scene, lower_extension(path), warnings);
  SkinnedMeshes skinned = collect_bones(scene, nodes, warnings);
  if (skinned.offset.empty()) skinned = collect_moved_nodes(scene, nodes, warnings);
  Skeleton skeleton = choose_links(nodes, skinned, warnings);
  if (skinned.moved_nodes.empty()) add_carried_meshes(scene, nodes, skeleton, skinned, warnings);
  mesh_bind_spaces(nodes, skinned);
  bind_poses(nodes, skinned, world, skeleton, warnings);
  place_carried_meshes(nodes, skeleton, skinned);
  LinkPoses poses(nodes, skeleton, world);
  const Motion motion = sample_motion(scene, nodes, skeleton, poses, options, warnings);

  SkinnedImport out;
  out.model =
      build_model(nodes, world, skeleton, motion.is_free, options, fs::path(path).stem().string());
  const std::size_t nl = skeleton.links.size();
  std::vector<int> model_link(nl);  // model link index of each link
  for (std::size_t k = 0; k < nl; ++k) model_link[k] = out.model->link_index(skeleton.link_name[k]);
  out.mesh = build_mesh(scene, nodes, skinned, world, skeleton, model_link,
                        image_reader_beside(path), warnings);
  for (const AnimInfo& info : motion.anims)
    check_budget(info, options.budget, options.frame_rate, out.model->nq);
  out.clips = build_clips(*out.model, model_link, skeleton, motion, poses, options.frame_rate);
  out.unit_scale = world.unit_scale;
  out.dropped_offset.assign(out.model->njoints, 0.0);
  for (std::size_t k = 0; k < nl; ++k) out.dropped_offset[model_link[k]] = motion.dropped[k];
  out.warnings = std::move(warnings.list());
  return out;
}

int import_in_child(const std::string& path, const ImportOptions& options, int fd) {
  std::string reply;
  try {
    Assimp::Importer importer;
    importer.SetIOHandler(new FolderIOSystem(fs::weakly_canonical(fs::path(path)).parent_path()));
    importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);
    importer.SetPropertyInteger(AI_CONFIG_PP_LBW_MAX_WEIGHTS, 4);
    const unsigned flags = aiProcess_Triangulate | aiProcess_LimitBoneWeights |
                           aiProcess_SortByPType | aiProcess_ValidateDataStructure;
    const aiScene* scene = importer.ReadFile(path, flags);
    if (scene == nullptr || scene->mRootNode == nullptr) {
      const std::string why = importer.GetErrorString();
      // assimp catches the allocation failure itself: it is the memory limit
      if (why.find("bad_alloc") != std::string::npos) throw std::bad_alloc();
      reply = encode_error_reply("assimp could not read it: " + why);
    } else {
      reply = encode_reply(convert_scene(*scene, path, options));
    }
  } catch (const std::bad_alloc&) {
    throw;  // the sandbox reports it as the memory limit
  } catch (const std::exception& e) {
    reply = encode_error_reply(e.what());
  }
  return write_all(fd, reply.data(), reply.size()) ? 0 : 1;
}

}  // namespace io::assimp_detail
