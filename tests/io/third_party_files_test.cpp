// Every clip and skinned-character file of assimp's own test models (Debian's assimp-testmodels,
// which scripts/deps installs): files nobody on the team wrote, many of them malformed on
// purpose (indices out of range, infinite values, recursive nodes, wrong JSON types, missing
// buffers). Each one must import into a valid model, clip and mesh, or be refused with a
// ModelError that names the file. Nothing else: no crash, no other exception, no hang.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "core/clip.hpp"
#include "core/data.hpp"
#include "core/kinematics.hpp"
#include "core/model_builder.hpp"
#include "core/skin.hpp"
#include "io/assimp_import.hpp"
#include "io/bvh_import.hpp"

namespace {

namespace fs = std::filesystem;

// $PINDRAG_THIRD_PARTY_MODELS_DIR, else where the Debian package puts them; empty when absent
std::string third_party_models_dir() {
  const char* e = std::getenv("PINDRAG_THIRD_PARTY_MODELS_DIR");
  const std::string dir = e && *e ? e : "/usr/share/assimp/models";
  return fs::is_directory(dir) ? dir : "";
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// the files a user can open as a clip or a character: sorted, so a failure names the same file
std::vector<std::string> clip_files(const std::string& dir) {
  std::vector<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::string ext = lower(entry.path().extension().string());
    if (ext == ".bvh" || ext == ".gltf" || ext == ".glb" || ext == ".fbx" || ext == ".dae") {
      files.push_back(entry.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

// every frame's link transforms are finite
void expect_finite_poses(const core::Model& model,
                         const core::Clip& clip,
                         const std::string& file) {
  core::Data data(model);
  for (int f = 0; f < clip.size(); ++f) {
    core::forward_kinematics(model, data, clip.frames[f]);
    for (int i = 0; i < model.njoints; ++i) {
      ASSERT_TRUE(data.X_W[i].R.allFinite() && data.X_W[i].p.allFinite())
          << file << ": frame " << f << ", link " << i;
    }
  }
}

// what the page draws from a skinned import must index what exists
void expect_valid_mesh(const core::Model& model,
                       const core::SkinnedMesh& mesh,
                       const std::string& file) {
  EXPECT_EQ(core::check_mesh_materials(mesh), "") << file;
  EXPECT_EQ(mesh.inverse_bind.size(), mesh.bones.size()) << file;
  for (const int bone : mesh.bones) {
    EXPECT_TRUE(bone >= 1 && bone < model.njoints) << file << ": bone link " << bone;
  }
  const int positions = static_cast<int>(mesh.positions.size());
  ASSERT_EQ(mesh.joints.size(), mesh.positions.size()) << file;
  ASSERT_EQ(mesh.weights.size(), mesh.positions.size()) << file;
  EXPECT_TRUE(mesh.normals.empty() || mesh.normals.size() == mesh.positions.size()) << file;
  for (int v = 0; v < positions; ++v) {
    ASSERT_TRUE(mesh.positions[v].allFinite()) << file << ": vertex " << v;
    float sum = 0;
    for (int k = 0; k < 4; ++k) {
      ASSERT_TRUE(std::isfinite(mesh.weights[v][k]) && mesh.weights[v][k] >= 0)
          << file << ": vertex " << v;
      ASSERT_TRUE(
          mesh.weights[v][k] == 0 ||
          (mesh.joints[v][k] >= 0 && mesh.joints[v][k] < static_cast<int>(mesh.bones.size())))
          << file << ": vertex " << v << " names skin joint " << mesh.joints[v][k];
      sum += mesh.weights[v][k];
    }
    ASSERT_NEAR(sum, 1.0f, 1e-4f) << file << ": vertex " << v;
  }
  for (const auto& t : mesh.triangles) {
    for (const int index : t) {
      ASSERT_TRUE(index >= 0 && index < positions) << file << ": triangle index " << index;
    }
  }
}

TEST(ThirdPartyFiles, EveryClipOrCharacterFileOfAssimpsTestModelsImportsOrIsRefusedByName) {
  const std::string dir = third_party_models_dir();
  if (dir.empty()) {
    GTEST_SKIP() << "assimp's test models not found (scripts/deps installs assimp-testmodels, or "
                    "set PINDRAG_THIRD_PARTY_MODELS_DIR); skipping";
  }
  const std::vector<std::string> files = clip_files(dir);
  ASSERT_GE(files.size(), 20u) << dir << " holds too few clip files to be the test models";
  int bvh_imported = 0, skinned_imported = 0, refused = 0;
  for (const std::string& file : files) {
    SCOPED_TRACE(file);
    try {
      if (lower(fs::path(file).extension().string()) == ".bvh") {
        const io::BvhImport imported = io::load_bvh_file(file);
        EXPECT_EQ(core::check_clip(*imported.model, imported.clip), "");
        expect_finite_poses(*imported.model, imported.clip, file);
        ++bvh_imported;
      } else {
        const io::SkinnedImport imported = io::import_skinned_file(file);
        ASSERT_GE(imported.model->njoints, 2);
        expect_valid_mesh(*imported.model, imported.mesh, file);
        for (const io::ImportedClip& c : imported.clips) {
          EXPECT_EQ(core::check_clip(*imported.model, c.clip), "");
          expect_finite_poses(*imported.model, c.clip, file);
        }
        ++skinned_imported;
      }
    } catch (const core::ModelError& e) {
      // the refusal names the file first, as every reader's messages do
      EXPECT_EQ(std::string(e.what()).rfind(file + ": ", 0), 0u) << e.what();
      ++refused;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "refused with another kind of error: " << e.what();
    }
  }
  std::printf("%zu files: %d BVH and %d skinned imported, %d refused by name\n", files.size(),
              bvh_imported, skinned_imported, refused);
  // the happy paths ran too: the package holds CMU BVH files and skinned glTF, FBX and COLLADA
  EXPECT_GE(bvh_imported, 1);
  EXPECT_GE(skinned_imported, 1);
}

// 64 boxes in a chain, each turned by a node animation and none skinned: the nodes the
// animation moves are the links, and each box, carried by a static node below its animated one,
// moves with that link
TEST(ThirdPartyFiles, AChainOfBoxesAnimatedWithoutBonesImportsAsTheNodesItMoves) {
  const std::string dir = third_party_models_dir();
  const std::string file = dir + "/Collada/anims_with_full_rotations_between_keys.DAE";
  if (dir.empty() || !fs::exists(file)) {
    GTEST_SKIP() << "assimp's test models not found (scripts/deps installs assimp-testmodels); "
                    "skipping";
  }
  const io::SkinnedImport imported = io::import_skinned_file(file);
  const core::Model& model = *imported.model;
  ASSERT_EQ(model.nlinks(), 64);
  EXPECT_EQ(model.link_name[1], "Box001");
  EXPECT_EQ(model.link_name[64], "Box064");
  // a box per link, each vertex on its link alone
  ASSERT_EQ(imported.mesh.parts.size(), 64u);
  EXPECT_EQ(imported.mesh.bones.size(), 64u);
  for (const auto& w : imported.mesh.weights) EXPECT_EQ(w[0], 1.0f);
  expect_valid_mesh(model, imported.mesh, file);
  // each box where its pivot node puts it: 64 boxes 1.89 m apart, a tower 120 m tall
  Eigen::Vector3f low = imported.mesh.positions.front(), high = low;
  for (const auto& p : imported.mesh.positions) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  EXPECT_NEAR((high - low).maxCoeff(), 120.18, 0.01);
  // the clip turns the boxes, the last one with every box below it
  ASSERT_EQ(imported.clips.size(), 1u);
  const core::Clip& clip = imported.clips[0].clip;
  ASSERT_GT(clip.size(), 10);
  core::Data first(model), later(model);
  core::forward_kinematics(model, first, clip.frames.front());
  double turned = 0;
  for (const Eigen::VectorXd& q : clip.frames) {
    core::forward_kinematics(model, later, q);
    turned =
        std::max(turned, Eigen::AngleAxisd(first.X_W[64].R.transpose() * later.X_W[64].R).angle());
  }
  EXPECT_GT(turned, 1.0);
}

}  // namespace
