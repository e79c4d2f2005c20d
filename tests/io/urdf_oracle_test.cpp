// Oracle tests for io/urdf.hpp: the world pose of every link of every shared URDF (and of
// the benchmark URDFs), on random configurations, agrees with MuJoCo 2.2.2 (mj_loadXML reads
// URDF) and with KDL (urdfdom + kdl_parser + TreeFkSolverPos_recursive) after the Z-up → Y-up
// change of basis: X_ours = (C R_peer Cᵀ, C p_peer). Joint values are mapped by joint name.
// A peer that cannot load a model is reported (with its error) as a skip, never a silent pass.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <tinyxml2.h>
#include <unistd.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <kdl/tree.hpp>
#include <kdl/treefksolverpos_recursive.hpp>
#include <kdl_parser/kdl_parser.hpp>
#include <map>

#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "io/urdf.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

namespace fs = std::filesystem;
using core::Matrix3;
using core::Transform;
using core::Vector3;

constexpr double kPoseTol = 1e-10;
constexpr int kSeeds = 5;

// world poses by link name, in the peer's (URDF, Z-up) world frame
using Poses = std::map<std::string, Transform>;
// joint values by joint name
using JointValues = std::map<std::string, double>;

std::vector<std::string> oracle_urdfs() {
  std::vector<std::string> out;
  auto add_dir = [&](const std::string& dir, bool recursive) {
    if (dir.empty() || !fs::is_directory(dir)) return;
    auto add = [&](const fs::directory_entry& e) {
      if (e.is_regular_file() && e.path().extension() == ".urdf") out.push_back(e.path().string());
    };
    if (recursive) {
      for (const auto& e : fs::recursive_directory_iterator(dir)) add(e);
    } else {
      for (const auto& e : fs::directory_iterator(dir)) add(e);
    }
  };
  if (!fixtures::data_dir().empty()) add_dir(fixtures::data_dir() + "/urdf", true);
  add_dir(fixtures::bench_models_dir(), false);
  std::sort(out.begin(), out.end());
  return out;
}

// ------------------------------------------------------------------------------------------------
// MuJoCo

// A copy of the URDF that MuJoCo 2.2.2 loads with every link kept as a body (platform.md §5):
// fusestatic and discardvisual off, mesh and non-standard geometry removed, massless links given
// a tiny mass and inertia. None of this changes a pose. Returns "" or the reason it failed.
std::string write_mujoco_copy(const std::string& urdf,
                              const fs::path& out,
                              std::vector<std::string>& notes) {
  tinyxml2::XMLDocument doc;
  if (doc.LoadFile(urdf.c_str()) != tinyxml2::XML_SUCCESS) return doc.ErrorStr();
  tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (!robot) return "no <robot> element";
  tinyxml2::XMLElement* mujoco = robot->FirstChildElement("mujoco");
  if (!mujoco) {
    mujoco = doc.NewElement("mujoco");
    robot->InsertFirstChild(mujoco);
  }
  tinyxml2::XMLElement* compiler = mujoco->FirstChildElement("compiler");
  if (!compiler) compiler = mujoco->InsertNewChildElement("compiler");
  compiler->SetAttribute("fusestatic", "false");
  compiler->SetAttribute("discardvisual", "false");
  int removed = 0, massless = 0;
  for (tinyxml2::XMLElement* link = robot->FirstChildElement("link"); link;
       link = link->NextSiblingElement("link")) {
    std::vector<tinyxml2::XMLElement*> drop;
    for (tinyxml2::XMLElement* e = link->FirstChildElement(); e; e = e->NextSiblingElement()) {
      const std::string tag = e->Name();
      if (tag != "visual" && tag != "collision") continue;
      const tinyxml2::XMLElement* g = e->FirstChildElement("geometry");
      const tinyxml2::XMLElement* shape = g ? g->FirstChildElement() : nullptr;
      const std::string type = shape ? shape->Name() : "";
      if (type != "box" && type != "sphere" && type != "cylinder") drop.push_back(e);
    }
    for (tinyxml2::XMLElement* e : drop) link->DeleteChild(e);
    removed += static_cast<int>(drop.size());
    if (std::string(link->Attribute("name") ? link->Attribute("name") : "") == "world") continue;
    tinyxml2::XMLElement* inertial = link->FirstChildElement("inertial");
    const tinyxml2::XMLElement* mass = inertial ? inertial->FirstChildElement("mass") : nullptr;
    if (mass && mass->DoubleAttribute("value") > 0) continue;
    ++massless;
    if (inertial) link->DeleteChild(inertial);
    inertial = link->InsertNewChildElement("inertial");
    inertial->InsertNewChildElement("mass")->SetAttribute("value", "1e-6");
    tinyxml2::XMLElement* I = inertial->InsertNewChildElement("inertia");
    for (const char* d : {"ixx", "iyy", "izz"}) I->SetAttribute(d, "1e-9");
    for (const char* o : {"ixy", "ixz", "iyz"}) I->SetAttribute(o, "0");
  }
  notes.push_back("MuJoCo copy: " + std::to_string(removed) +
                  " mesh or non-standard shapes removed, " + std::to_string(massless) +
                  " massless links given 1e-6 kg");
  if (doc.SaveFile(out.c_str()) != tinyxml2::XML_SUCCESS) return doc.ErrorStr();
  return "";
}

class MujocoPeer {
 public:
  MujocoPeer(const std::string& urdf, const fs::path& scratch) {
    const fs::path copy = scratch / ("mujoco_" + fs::path(urdf).filename().string());
    error = write_mujoco_copy(urdf, copy, notes);
    if (!error.empty()) return;
    char err[1000] = "";
    model_ = mj_loadXML(copy.c_str(), nullptr, err, sizeof err);
    if (!model_) {
      error = err;
      return;
    }
    data_ = mj_makeData(model_);
  }
  ~MujocoPeer() {
    if (data_) mj_deleteData(data_);
    if (model_) mj_deleteModel(model_);
  }
  MujocoPeer(const MujocoPeer&) = delete;
  MujocoPeer& operator=(const MujocoPeer&) = delete;

  bool ok() const { return model_ != nullptr; }

  // every MuJoCo joint must get a value; returns "" or the first joint without one
  std::string poses(const JointValues& q, Poses& out) {
    mj_resetData(model_, data_);
    for (int j = 0; j < model_->njnt; ++j) {
      const char* name = mj_id2name(model_, mjOBJ_JOINT, j);
      const auto it = name ? q.find(name) : q.end();
      if (it == q.end()) return std::string("MuJoCo joint '") + (name ? name : "?") + "' unmapped";
      if (model_->jnt_type[j] != mjJNT_HINGE && model_->jnt_type[j] != mjJNT_SLIDE) {
        return std::string("MuJoCo joint '") + name + "' is not 1-DOF";
      }
      data_->qpos[model_->jnt_qposadr[j]] = it->second;
    }
    mj_kinematics(model_, data_);
    out.clear();
    for (int b = 1; b < model_->nbody; ++b) {
      const char* name = mj_id2name(model_, mjOBJ_BODY, b);
      if (!name) continue;
      Transform X;
      for (int r = 0; r < 3; ++r) {
        X.p[r] = data_->xpos[3 * b + r];
        for (int c = 0; c < 3; ++c) X.R(r, c) = data_->xmat[9 * b + 3 * r + c];  // row-major
      }
      out[name] = X;
    }
    return "";
  }

  std::string error;
  std::vector<std::string> notes;

 private:
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
};

// ------------------------------------------------------------------------------------------------
// KDL (urdf::parseURDFFile then treeFromUrdfModel; kdl_parser::treeFromFile crashes on bad input)

class KdlPeer {
 public:
  explicit KdlPeer(const std::string& urdf) {
    const urdf::ModelInterfaceSharedPtr model = urdf::parseURDFFile(urdf);
    if (!model) {
      error = "urdf::parseURDFFile failed";
      return;
    }
    if (!kdl_parser::treeFromUrdfModel(*model, tree_)) {
      error = "kdl_parser::treeFromUrdfModel failed";
      return;
    }
    ok_ = true;
  }
  bool ok() const { return ok_; }

  std::string poses(const JointValues& values, Poses& out) {
    KDL::TreeFkSolverPos_recursive fk(tree_);
    KDL::JntArray q(tree_.getNrOfJoints());
    for (const auto& [name, element] : tree_.getSegments()) {
      const KDL::Joint& joint = GetTreeElementSegment(element).getJoint();
      if (joint.getType() == KDL::Joint::None) continue;
      const auto it = values.find(joint.getName());
      if (it == values.end()) return "KDL joint '" + joint.getName() + "' unmapped";
      q(GetTreeElementQNr(element)) = it->second;
    }
    out.clear();
    for (const auto& [name, element] : tree_.getSegments()) {
      KDL::Frame f;
      if (fk.JntToCart(q, f, name) < 0) return "KDL FK failed for segment '" + name + "'";
      Transform X;
      for (int r = 0; r < 3; ++r) {
        X.p[r] = f.p(r);
        for (int c = 0; c < 3; ++c) X.R(r, c) = f.M(r, c);
      }
      out[name] = X;
    }
    return "";
  }

  std::string error;

 private:
  KDL::Tree tree_;
  bool ok_ = false;
};

// ------------------------------------------------------------------------------------------------

// largest entry-wise difference between our pose and (C R Cᵀ, C p) of the peer's, over all links
double max_pose_error(const core::Model& m,
                      const core::Data& d,
                      const Poses& peer,
                      std::string& missing) {
  const Matrix3 C = io::urdf_to_y_up();
  double err = 0;
  for (int i = 1; i < m.njoints; ++i) {
    const auto it = peer.find(m.link_name[i]);
    if (it == peer.end()) {
      missing = m.link_name[i];
      return std::numeric_limits<double>::infinity();
    }
    const Matrix3 R = C * it->second.R * C.transpose();
    const Vector3 p = C * it->second.p;
    err = std::max(
        {err, (d.X_W[i].R - R).cwiseAbs().maxCoeff(), (d.X_W[i].p - p).cwiseAbs().maxCoeff()});
  }
  return err;
}

class ScratchDir {
 public:
  ScratchDir()
      : path_(fs::temp_directory_path() / ("pindrag_urdf_oracle_" + std::to_string(::getpid()))) {
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

enum class Peer { kMujoco, kKdl };

void check_against(Peer which) {
  const std::vector<std::string> files = oracle_urdfs();
  if (files.empty()) GTEST_SKIP() << "neither the shared data nor the benchmark folder is present";
  const char* peer_name = which == Peer::kMujoco ? "MuJoCo" : "KDL";
  ScratchDir scratch;
  std::vector<std::string> refused;
  double worst = 0;
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    const io::LoadResult ours = io::load_urdf_file(path);  // root as in the file
    const core::Model& m = *ours.model;

    std::unique_ptr<MujocoPeer> mujoco;
    std::unique_ptr<KdlPeer> kdl;
    std::string peer_error;
    if (which == Peer::kMujoco) {
      mujoco = std::make_unique<MujocoPeer>(path, scratch.path());
      if (!mujoco->ok()) peer_error = mujoco->error;
    } else {
      kdl = std::make_unique<KdlPeer>(path);
      if (!kdl->ok()) peer_error = kdl->error;
    }
    if (!peer_error.empty()) {
      refused.push_back(fs::path(path).filename().string() + ": " + peer_error);
      continue;
    }

    core::Data data(m);
    double model_worst = 0;
    for (int seed = 1; seed <= kSeeds; ++seed) {
      const Eigen::VectorXd q = core::random_configuration(m, seed);
      JointValues values;
      for (int i = 1; i < m.njoints; ++i) {
        if (core::joint_nv(m.joint_type[i]) == 1) values[m.joint_name[i]] = q[m.idx_q[i]];
      }
      core::forward_kinematics(m, data, q);
      Poses peer;
      const std::string failure = mujoco ? mujoco->poses(values, peer) : kdl->poses(values, peer);
      ASSERT_EQ(failure, "");
      std::string missing;
      const double err = max_pose_error(m, data, peer, missing);
      ASSERT_EQ(missing, "") << "link missing in " << peer_name;
      EXPECT_LE(err, kPoseTol) << "seed " << seed;
      model_worst = std::max(model_worst, err);
    }
    worst = std::max(worst, model_worst);
    std::cout << "[ " << peer_name << " ] " << fs::path(path).filename().string() << ": "
              << m.nlinks() << " links, " << m.nv << " dof, max pose error " << std::scientific
              << std::setprecision(2) << model_worst << std::defaultfloat;
    if (mujoco) {
      for (const std::string& note : mujoco->notes) std::cout << "; " << note;
    }
    std::cout << "\n";
  }
  std::cout << "[ " << peer_name << " ] largest error over all models " << std::scientific
            << std::setprecision(2) << worst << std::defaultfloat << "\n";
  ::testing::Test::RecordProperty(std::string(peer_name) + "_max_pose_error",
                                  std::to_string(worst));
  if (!refused.empty()) {
    std::string why;
    for (const std::string& r : refused) why += "\n  " + r;
    GTEST_SKIP() << peer_name << " could not load " << refused.size() << " of " << files.size()
                 << " models (the others were compared):" << why;
  }
}

TEST(UrdfOracle, AllLinkPosesAgreeWithMujoco) { check_against(Peer::kMujoco); }

TEST(UrdfOracle, AllLinkPosesAgreeWithKdl) { check_against(Peer::kKdl); }

}  // namespace
