// Tests for animator/facing.hpp: which way a figure faces, read from the left and right links its
// names tell (else from where its toes point), and face_forward turning an opened figure (and its
// clip) to face +Z in place. The checks use what each reading does not: where the toes point,
// which side the left hand is on, the other reading.
#include "animator/facing.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <numbers>

#include "core/configuration.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "core/model_builder.hpp"
#include "core/model_edit.hpp"
#include "io/bvh.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using animator::face_forward;
using animator::mirrored_name;
using core::Vector3;

// the horizontal direction from the feet to the toes, both sides summed, normalised
Vector3 toes_direction(const core::Model& m, const core::Data& d) {
  Vector3 v = d.X_W[m.link_index("l_toes")].p - d.X_W[m.link_index("l_foot")].p +
              d.X_W[m.link_index("r_toes")].p - d.X_W[m.link_index("r_foot")].p;
  v.y() = 0;
  return v.normalized();
}

// a box link on a free root joint placed `height` up
core::LinkSpec free_root(const std::string& name, double mass, const Vector3& half, double height) {
  core::LinkSpec l = fixtures::box_link(name, "", mass, half);
  l.joint.type = core::JointType::kFree;
  l.joint.X_PJ = core::Transform::from_translation(Vector3(0, height, 0));
  return l;
}

// a small box link hung from `parent` at `offset` on a joint of `type`
core::LinkSpec hung(const std::string& name,
                    const std::string& parent,
                    core::JointType type,
                    const Vector3& offset) {
  core::LinkSpec l = fixtures::box_link(name, parent, 1, Vector3(0.05, 0.05, 0.05));
  l.joint.type = type;
  l.joint.X_PJ = core::Transform::from_translation(offset);
  return l;
}

TEST(MirroredName, SwapsTheSideWordInItsOwnCase) {
  const auto expect = [](const char* name, const char* mirrored, bool left) {
    const auto m = mirrored_name(name);
    ASSERT_TRUE(m) << name;
    EXPECT_EQ(m->first, mirrored) << name;
    EXPECT_EQ(m->second, left) << name;
  };
  expect("LeftUpLeg", "RightUpLeg", true);
  expect("mixamorig:RightArm", "mixamorig:LeftArm", false);
  expect("leg_joint_L_1", "leg_joint_R_1", true);
  expect("Bip01 R Thigh", "Bip01 L Thigh", false);
  expect("hip.L", "hip.R", true);
  expect("left_hip_pitch_link", "right_hip_pitch_link", true);
  expect("LHip", "RHip", true);
  expect("RIGHT_ARM", "LEFT_ARM", false);
  expect("b_LeftLeg01_019", "b_RightLeg01_019", true);
  // four-legged robots' leg codes: fore/hind then side, or side then fore/hind
  expect("FL_hip_joint", "FR_hip_joint", true);
  expect("RR_calf", "RL_calf", false);
  expect("rl_thigh", "rr_thigh", true);
  expect("LF_HAA", "RF_HAA", true);
  expect("RH_KFE", "LH_KFE", false);
  // no side word: a word that only starts with L or R is not one
  for (const char* name :
       {"Hips", "Leg", "Lumbar", "Root", "lthigh", "Ribs_2", "LowerBack", "FF_x", "LR_2", "LL"}) {
    EXPECT_FALSE(mirrored_name(name)) << name;
  }
}

TEST(FacingDirection, TheBundledFigureFacesPlusZAndTurnsBackWhenTurned) {
  const auto m = core::build_human_figure({});
  core::Data d(*m);
  const Eigen::VectorXd q = core::rest_configuration(*m);
  core::forward_kinematics(*m, d, q);
  const auto pairs = animator::left_right_pairs(*m);
  ASSERT_EQ(pairs.size(), 2u);  // hips and shoulders
  const auto facing = animator::facing_from_sides(d, pairs);
  ASSERT_TRUE(facing);
  EXPECT_LT((*facing - Vector3::UnitZ()).norm(), 1e-9);
  EXPECT_GT(toes_direction(*m, d).z(), 0.99);
  // already facing +Z: the model itself
  const animator::Faced same = face_forward(m, q);
  EXPECT_TRUE(same.known);
  EXPECT_EQ(same.model, m);

  // turned 110° about a vertical line away from the origin, it turns back in place
  const core::Matrix3 yaw =
      Eigen::AngleAxisd(110 * std::numbers::pi / 180, Vector3::UnitY()).toRotationMatrix();
  const auto turned = core::turn_root(*m, yaw, Vector3(2.0, 0.0, -1.0));
  core::Data dt(*turned);
  core::forward_kinematics(*turned, dt, q);
  EXPECT_LT(toes_direction(*turned, dt).z(), 0.0);
  const animator::Faced back = face_forward(turned, q);
  ASSERT_TRUE(back.known);
  EXPECT_NEAR(back.turn, -110 * std::numbers::pi / 180, 1e-9);
  core::Data db(*back.model);
  core::forward_kinematics(*back.model, db, q);
  EXPECT_GT(toes_direction(*back.model, db).z(), 1 - 1e-9);
  // its left hand to +X, the root where it stood, every link at its height
  EXPECT_GT(db.X_W[m->link_index("l_hand")].p.x(), db.X_W[m->link_index("r_hand")].p.x());
  EXPECT_LT((db.X_W[1].p - dt.X_W[1].p).norm(), 1e-12);
  for (int i = 1; i < m->njoints; ++i) EXPECT_NEAR(db.X_W[i].p.y(), dt.X_W[i].p.y(), 1e-12);
  // and again: itself
  EXPECT_EQ(face_forward(back.model, q).model, back.model);
}

TEST(FacingDirection, AClipTurnsWithItsFirstFrame) {
  const auto m = core::build_human_figure({});
  // a figure walking along -X, facing -X (its root yawed -90°) from its first frame on
  std::vector<Eigen::VectorXd> frames;
  for (int k = 0; k < 5; ++k) {
    Eigen::VectorXd q = core::rest_configuration(*m);
    const core::Quaternion yaw(Eigen::AngleAxisd(-std::numbers::pi / 2, Vector3::UnitY()));
    core::set_quaternion_at(q, m->idx_q[1] + 3, yaw);
    q[m->idx_q[1]] = 1.0 - 0.3 * k;
    frames.push_back(q);
  }
  const animator::Faced f = face_forward(m, frames.front());
  ASSERT_TRUE(f.known);
  EXPECT_NEAR(f.turn, std::numbers::pi / 2, 1e-9);
  core::Data d(*f.model);
  core::forward_kinematics(*f.model, d, frames.front());
  const Vector3 start = d.X_W[1].p;
  for (const Eigen::VectorXd& q : frames) {
    core::forward_kinematics(*f.model, d, q);
    EXPECT_GT(toes_direction(*f.model, d).z(), 1 - 1e-9);
  }
  // the walk goes the way it faces, +Z, from where it started
  EXPECT_NEAR(d.X_W[1].p.z() - start.z(), 1.2, 1e-9);
  EXPECT_NEAR(d.X_W[1].p.x() - start.x(), 0.0, 1e-9);
}

// a four-legged figure named by side words, facing +X: its left legs at -Z
std::shared_ptr<const core::Model> quadruped() {
  core::ModelBuilder b("quadruped");
  b.add_link(free_root("body", 20, Vector3(0.8, 0.3, 0.3), 0.0));
  for (const char* side : {"L", "R"}) {
    for (const char* end : {"front", "back"}) {
      const std::string leg = std::string("leg_") + side + "_" + end;
      const double x = std::string(end) == "front" ? 0.35 : -0.35;
      const double z = std::string(side) == "L" ? -0.12 : 0.12;
      b.add_link(hung(leg, "body", core::JointType::kSpherical, Vector3(x, -0.1, z)));
      // the foot is a pair too, splayed outwards: only each limb's first pair counts
      b.add_link(hung(leg + "_foot", leg, core::JointType::kFixed, Vector3(0.3, -0.3, 2 * z)));
    }
  }
  return b.finalize();
}

// a four-legged robot named by leg codes (FL, FR, RL, RR), facing +X: its left legs at -Z
TEST(FacingDirection, LegCodesTellAFourLeggedRobotsLeft) {
  core::ModelBuilder b("robot");
  b.add_link(free_root("trunk", 10, Vector3(0.3, 0.1, 0.1), 0.0));
  for (const char* leg : {"FL", "FR", "RL", "RR"}) {
    const double x = leg[0] == 'F' ? 0.2 : -0.2, z = leg[1] == 'L' ? -0.05 : 0.05;
    const std::string hip = std::string(leg) + "_hip";
    b.add_link(hung(hip, "trunk", core::JointType::kSpherical, Vector3(x, 0, z)));
    b.add_link(hung(std::string(leg) + "_foot", hip, core::JointType::kFixed, Vector3(0, -0.3, 0)));
  }
  const auto robot = b.finalize();
  EXPECT_EQ(animator::left_right_pairs(*robot).size(), 2u);
  const animator::Faced f = face_forward(robot, core::rest_configuration(*robot));
  ASSERT_TRUE(f.known);
  EXPECT_NEAR(f.turn, -std::numbers::pi / 2, 1e-9);
}

TEST(FacingDirection, SideWordsTellAQuadrupedsLeftFromItsFirstPairPerLeg) {
  const auto m = quadruped();
  const auto pairs = animator::left_right_pairs(*m);
  ASSERT_EQ(pairs.size(), 2u);
  for (const auto& [l, r] : pairs) {
    EXPECT_EQ(m->link_name[l].substr(0, 6), "leg_L_");
    EXPECT_EQ(m->link_name[r], "leg_R_" + m->link_name[l].substr(6));
    EXPECT_EQ(m->link_name[l].find("foot"), std::string::npos);
  }
  const Eigen::VectorXd q = core::rest_configuration(*m);
  const animator::Faced f = face_forward(m, q);
  ASSERT_TRUE(f.known);
  EXPECT_NEAR(f.turn, -std::numbers::pi / 2, 1e-9);
  core::Data d(*f.model);
  core::forward_kinematics(*f.model, d, q);
  // front legs ahead (+Z), left legs at +X
  EXPECT_NEAR(d.X_W[f.model->link_index("leg_L_front")].p.z() -
                  d.X_W[f.model->link_index("leg_L_back")].p.z(),
              0.7, 1e-9);
  EXPECT_NEAR(d.X_W[f.model->link_index("leg_L_front")].p.x() -
                  d.X_W[f.model->link_index("leg_R_front")].p.x(),
              0.24, 1e-9);
}

TEST(FacingDirection, AFigureLyingOnItsSideOrWithoutSidesKeepsItsPlacement) {
  const auto m = core::build_human_figure({});
  Eigen::VectorXd q = core::rest_configuration(*m);
  // lying on its left side: the hips one above the other
  const core::Quaternion roll(Eigen::AngleAxisd(std::numbers::pi / 2, Vector3::UnitZ()));
  core::set_quaternion_at(q, m->idx_q[1] + 3, roll);
  const animator::Faced lying = face_forward(m, q);
  EXPECT_FALSE(lying.known);
  EXPECT_EQ(lying.model, m);
  // nothing named by side
  core::ModelBuilder b("stick");
  b.add_link(free_root("base", 1, Vector3(0.1, 0.1, 0.1), 0.0));
  b.add_link(hung("tip", "base", core::JointType::kFixed, Vector3(0, 0.2, 0)));
  const auto stick = b.finalize();
  const animator::Faced unknown = face_forward(stick, core::rest_configuration(*stick));
  EXPECT_FALSE(unknown.known);
  EXPECT_EQ(unknown.model, stick);
}

// Each of the four quarter turns and the half turn that take +Y off the vertical: the figure
// stands upright again, every link where it was in the rest pose.
TEST(StandUpright, AFigureAuthoredWithAnotherUpAxisStandsAsItWasBuilt) {
  const auto m = core::build_human_figure({});
  const Eigen::VectorXd q = core::rest_configuration(*m);
  core::Data built(*m);
  core::forward_kinematics(*m, built, q);
  const Vector3 root = built.X_W[1].p;
  ASSERT_TRUE(animator::rest_up(*m));
  EXPECT_GT(animator::rest_up(*m)->y(), 0.99);
  EXPECT_EQ(animator::stand_upright(m), m);
  const double quarter = std::numbers::pi / 2;
  const std::pair<double, Vector3> turns[] = {{quarter, Vector3::UnitX()},
                                              {-quarter, Vector3::UnitX()},
                                              {quarter, Vector3::UnitZ()},
                                              {-quarter, Vector3::UnitZ()},
                                              {2 * quarter, Vector3::UnitX()}};
  for (const auto& [angle, axis] : turns) {
    const auto lying = core::turn_root(*m, Eigen::AngleAxisd(angle, axis).toRotationMatrix(), root);
    // its up (feet to hips to head) now along another axis, to within the few degrees its feet
    // stand off the line of its spine
    const core::Matrix3 R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    EXPECT_GT(animator::rest_up(*lying)->dot(R * Vector3::UnitY()), 0.99)
        << angle << " about " << axis.transpose();
    const auto upright = animator::stand_upright(lying);
    core::Data d(*upright);
    core::forward_kinematics(*upright, d, q);
    for (int i = 1; i < m->njoints; ++i) {
      EXPECT_LT((d.X_W[i].p - built.X_W[i].p).norm(), 1e-12)
          << m->link_name[i] << ", " << angle << " about " << axis.transpose();
    }
  }
  // leaning 30° is a pose, not an axis convention: kept
  const auto leaning = core::turn_root(
      *m, Eigen::AngleAxisd(std::numbers::pi / 6, Vector3::UnitX()).toRotationMatrix(), root);
  EXPECT_EQ(animator::stand_upright(leaning), leaning);
}

// A four-legged figure named like a biped (Hips, Head, LeftFoot, ...), its spine level and its
// legs under it: its hips-to-head is horizontal, but it is not lying down
TEST(StandUpright, AFourLeggedFigureNamedLikeABipedIsNotStoodOnItsHindLegs) {
  core::ModelBuilder b("dog");
  b.add_link(free_root("Hips", 10, Vector3(0.1, 0.1, 0.1), 0.5));
  b.add_link(hung("Spine", "Hips", core::JointType::kSpherical, Vector3(0, 0, 0.3)));
  b.add_link(hung("Head", "Spine", core::JointType::kSpherical, Vector3(0, 0.1, 0.3)));
  for (const std::string side : {"Left", "Right"}) {
    const double x = side == "Left" ? 0.1 : -0.1;
    b.add_link(hung(side + "UpLeg", "Hips", core::JointType::kSpherical, Vector3(x, 0, 0)));
    b.add_link(hung(side + "Foot", side + "UpLeg", core::JointType::kFixed, Vector3(0, -0.45, 0)));
  }
  const auto dog = b.finalize();
  EXPECT_FALSE(animator::rest_up(*dog));
  EXPECT_EQ(animator::stand_upright(dog), dog);
  // the same figure exported Z up is not guessed at either: it keeps its file's axes
  const auto z_up = core::turn_root(
      *dog, Eigen::AngleAxisd(std::numbers::pi / 2, Vector3::UnitX()).toRotationMatrix(),
      Vector3::Zero());
  EXPECT_EQ(animator::stand_upright(z_up), z_up);
}

// the bundled figure with its links named n1, n2, ... (a glTF whose bones have no names)
std::shared_ptr<const core::Model> nameless_figure() {
  const auto m = core::build_human_figure({});
  core::ModelBuilder b = core::to_builder(*m);
  for (int i = 1; i < m->njoints; ++i) {
    core::LinkSpec& l = b.link(i - 1);
    l.name = "n" + std::to_string(i);
    l.joint.name = "j" + std::to_string(i);
    l.display_name.clear();
    if (m->parent[i] > 0) l.parent = "n" + std::to_string(m->parent[i]);
  }
  return b.finalize();
}

TEST(FacingFromToes, ANamelessFigureFacesWhereItsToesPoint) {
  const auto m = nameless_figure();
  EXPECT_TRUE(animator::left_right_pairs(*m).empty());
  const auto toes = animator::toe_links(*m);
  ASSERT_EQ(toes.size(), 2u);
  const auto built = core::build_human_figure({});
  for (const auto& [foot, toe] : toes) {
    const std::string name = built->link_name[toe];
    EXPECT_TRUE(name == "l_toes" || name == "r_toes") << name;
    EXPECT_EQ(built->link_name[foot], name.substr(0, 2) + "foot");
  }
  // the first frame yawed 60° and leaning forward 20°: turned back by -60°
  Eigen::VectorXd q = core::rest_configuration(*m);
  const core::Quaternion pose(Eigen::AngleAxisd(std::numbers::pi / 3, Vector3::UnitY()) *
                              Eigen::AngleAxisd(std::numbers::pi / 9, Vector3::UnitX()));
  core::set_quaternion_at(q, m->idx_q[1] + 3, pose);
  const animator::Faced f = face_forward(m, q);
  ASSERT_TRUE(f.known);
  EXPECT_NEAR(f.turn, -std::numbers::pi / 3, 1e-9);
  core::Data d(*f.model);
  core::forward_kinematics(*f.model, d, q);
  const auto facing = animator::facing_of(*f.model, d);
  ASSERT_TRUE(facing);
  EXPECT_TRUE(facing->by_toes);
  EXPECT_LT((facing->direction - Vector3::UnitZ()).norm(), 1e-9);
  // the left hip (the bundled figure's l_thigh) at +X
  const int l_thigh = built->link_index("l_thigh"), r_thigh = built->link_index("r_thigh");
  EXPECT_GT(d.X_W[l_thigh].p.x() - d.X_W[r_thigh].p.x(), 0.1);
  EXPECT_NEAR(d.X_W[l_thigh].p.z(), d.X_W[r_thigh].p.z(), 1e-9);
}

TEST(FacingFromToes, FeetWithoutToesOrPointingApartTellNothing) {
  // a figure whose lowest leaves hang straight down from their parents
  core::ModelBuilder b("plumb");
  b.add_link(free_root("body", 10, Vector3(0.2, 0.3, 0.1), 1.0));
  for (const double x : {-0.1, 0.1}) {
    const std::string leg = x < 0 ? "a" : "b";
    b.add_link(hung(leg, "body", core::JointType::kSpherical, Vector3(x, -0.2, 0)));
    b.add_link(hung(leg + "_end", leg, core::JointType::kFixed, Vector3(0, -0.7, 0)));
  }
  const auto plumb = b.finalize();
  EXPECT_TRUE(animator::toe_links(*plumb).empty());
  EXPECT_FALSE(face_forward(plumb, core::rest_configuration(*plumb)).known);
  // feet splayed apart, one +X and one -X: no agreement, no direction
  core::ModelBuilder splayed = core::to_builder(*plumb);
  splayed.link(2).joint.X_PJ = core::Transform::from_translation(Vector3(-0.3, -0.7, 0));
  splayed.link(4).joint.X_PJ = core::Transform::from_translation(Vector3(0.3, -0.7, 0));
  EXPECT_TRUE(animator::toe_links(*splayed.finalize()).empty());
}

// Where both readings exist on the shared captures, the names' left and right and the toes found
// by shape agree (measured: within 3.4°, where the clips start)
TEST(FacingFromToes, AgreesWithTheSidesOnTheSharedCaptures) {
  PINDRAG_REQUIRE_DATA_DIR();
  int compared = 0;
  for (const auto& entry : std::filesystem::directory_iterator(fixtures::data_dir() + "/bvh")) {
    const io::BvhImport imported = io::load_bvh_file(entry.path().string());
    const core::Model& m = *imported.model;
    core::Data d(m);
    core::forward_kinematics(m, d, imported.clip.frames.front());
    const auto sides = animator::facing_from_sides(d, animator::left_right_pairs(m));
    const auto toes = animator::facing_from_toes(m, d, animator::toe_links(m));
    if (!sides || !toes) continue;
    const double degrees =
        std::acos(std::clamp(sides->dot(*toes), -1.0, 1.0)) * 180 / std::numbers::pi;
    std::cout << entry.path().filename().string() << ": sides and toes " << degrees << "° apart\n";
    EXPECT_LT(degrees, 10.0) << entry.path();
    ++compared;
  }
  EXPECT_GE(compared, 5);
}

}  // namespace
