// A character opened in the page (server/uploads.hpp session_from_file) faces +Z where its clip
// starts. The turn is read from the figure's left and right hips and shoulders (else its toes);
// these tests check it with what that reading does not use: where the toes point, which side a
// left leg ends up on, where the knees are.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>

#include "animator/joint_names.hpp"
#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "server/uploads.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using animator::BodyPart;
using core::Vector3;

// the pose where posing starts: the clip's first frame, else the rest configuration
Eigen::VectorXd first_pose(const animator::Session& s) {
  return s.clip() ? s.clip()->frames.front() : core::rest_configuration(s.model());
}

// the horizontal angle (degrees) of the feet-to-toes direction from +Z, both sides summed;
// NaN when the names tell no feet and toes
double toes_angle_from_plus_z(const core::Model& m, const Eigen::VectorXd& q) {
  const animator::BodyPartGuess parts = animator::guess_body_parts(m);
  const auto link = [&](BodyPart p) { return parts.link[static_cast<int>(p)]; };
  for (BodyPart p :
       {BodyPart::kLeftFoot, BodyPart::kLeftToes, BodyPart::kRightFoot, BodyPart::kRightToes}) {
    if (link(p) < 0) return std::nan("");
  }
  core::Data d(m);
  core::forward_kinematics(m, d, q);
  const Vector3 v = d.X_W[link(BodyPart::kLeftToes)].p - d.X_W[link(BodyPart::kLeftFoot)].p +
                    d.X_W[link(BodyPart::kRightToes)].p - d.X_W[link(BodyPart::kRightFoot)].p;
  return std::atan2(v.x(), v.z()) * 180 / std::numbers::pi;
}

// the world position of a link by name, and a capture's left hip from its right
Vector3 link_at(const core::Model& m, const core::Data& d, const char* name) {
  return d.X_W[m.link_index(name)].p;
}
Vector3 hips_left(const core::Model& m, const core::Data& d) {
  return link_at(m, d, "LeftUpLeg") - link_at(m, d, "RightUpLeg");
}

TEST(OpenedPlacement, ACaptureFacingPlusXOpensFacingPlusZ) {
  // hips 0.9 m up; legs at ±10 cm along X with feet and toes; the root yawed 90° in its first
  // frame (facing +X, its left towards -Z), walking along +X
  const std::string leg =
      "  CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "  JOINT %sLeg\n  {\n   OFFSET 0 -45 0\n   CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "   JOINT %sFoot\n   {\n    OFFSET 0 -40 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "    JOINT %sToeBase\n    {\n     OFFSET 0 -5 12\n     CHANNELS 3 Zrotation Xrotation "
      "Yrotation\n     End Site\n     {\n      OFFSET 0 0 5\n     }\n    }\n   }\n  }\n }\n";
  std::string bvh =
      "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n"
      " CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n";
  for (const char* side : {"Left", "Right"}) {
    bvh += std::string(" JOINT ") + side + "UpLeg\n {\n  OFFSET " +
           (side[0] == 'L' ? "10" : "-10") + " 0 0\n";
    std::string l = leg;
    for (std::size_t at; (at = l.find("%s")) != std::string::npos;) l.replace(at, 2, side);
    bvh += l;
  }
  bvh += "}\nMOTION\nFrames: 3\nFrame Time: 0.033333\n";
  for (int f = 0; f < 3; ++f) {
    bvh += std::to_string(300 + 40 * f) + " 90 0 0 0 90";
    for (int k = 0; k < 8 * 3; ++k) bvh += " 0";
    bvh += "\n";
  }
  const std::filesystem::path path =
      std::filesystem::path(::testing::TempDir()) / "facing_plus_x.bvh";
  std::ofstream(path) << bvh;
  const auto s = server::session_from_file(path.string(), "facing");
  const core::Model& m = s->model();
  core::Data d(m);
  // every frame: left leg towards +X, toes towards +Z; the walk goes along +Z, 80 file units
  // (4 hip widths: the file's unit is guessed, so lengths are compared with the hips')
  std::vector<Vector3> hips;
  double hip_width = 0;
  for (const Eigen::VectorXd& q : s->clip()->frames) {
    core::forward_kinematics(m, d, q);
    const Vector3 left = hips_left(m, d);
    EXPECT_GT(left.x(), 0.0);
    EXPECT_NEAR(left.y(), 0.0, 1e-12);
    EXPECT_NEAR(left.z(), 0.0, 1e-12);
    EXPECT_NEAR(toes_angle_from_plus_z(m, q), 0.0, 1e-6);
    hips.push_back(link_at(m, d, "Hips"));
    hip_width = left.norm();
  }
  EXPECT_NEAR(hips[2].z() - hips[0].z(), 4 * hip_width, 1e-9);
  EXPECT_NEAR(hips[2].x() - hips[0].x(), 0.0, 1e-9);
}

// every character of the shared data opens facing +Z as far as its toes tell (the hips and
// shoulders decide the turn; feet may turn out by a few degrees, so the bound is 20°); files whose
// names tell no sides keep their own orientation
TEST(OpenedPlacement, EverySharedFigureWithToesOpensWithThemPointingPlusZ) {
  PINDRAG_REQUIRE_DATA_DIR();
  int checked = 0;
  for (const char* folder : {"bvh", "gltf", "urdf"}) {
    for (const auto& entry :
         std::filesystem::directory_iterator(fixtures::data_dir() + "/" + folder)) {
      if (!entry.is_regular_file()) continue;
      const std::string path = entry.path().string();
      const auto s = server::session_from_file(path, "shared");
      const double angle = toes_angle_from_plus_z(s->model(), first_pose(*s));
      std::cout << entry.path().filename().string() << ": toes at " << angle << "° from +Z\n";
      if (std::isnan(angle)) continue;
      EXPECT_LT(std::abs(angle), 20.0) << path;
      ++checked;
    }
  }
  // the captures with named feet and toes: boxing (facing -Z in its file), both CMU walks, the
  // CMU jumps, Mixamo, PFNN
  EXPECT_GE(checked, 6);
}

// A capture exported Z up, facing -Y (as Blender's axes are): it opens standing on its feet on
// the ground, facing +Z, walking along +Z.
TEST(OpenedPlacement, ACaptureAuthoredZUpOpensStandingUpright) {
  std::string bvh =
      "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n"
      " CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n";
  const char* rot = "CHANNELS 3 Zrotation Xrotation Yrotation\n";
  for (const std::string side : {"Left", "Right"}) {
    bvh += " JOINT " + side + "UpLeg\n {\n  OFFSET " + (side == "Left" ? "10" : "-10") +
           " 0 0\n  " + rot + "  JOINT " + side + "Leg\n  {\n   OFFSET 0 0 -45\n   " + rot +
           "   JOINT " + side + "Foot\n   {\n    OFFSET 0 0 -40\n    " + rot + "    JOINT " + side +
           "ToeBase\n    {\n     OFFSET 0 -12 -5\n     " + rot +
           "     End Site\n     {\n      OFFSET 0 -5 0\n     }\n    }\n   }\n  }\n }\n";
  }
  bvh += " JOINT Spine\n {\n  OFFSET 0 0 10\n  " + std::string(rot) +
         "  JOINT Head\n  {\n   OFFSET 0 0 50\n   " + rot +
         "   End Site\n   {\n    OFFSET 0 0 10\n   }\n  }\n }\n}\n";
  bvh += "MOTION\nFrames: 2\nFrame Time: 0.033333\n";
  for (int f = 0; f < 2; ++f) {
    bvh += "0 " + std::to_string(-40 * f) + " 90 0 0 0";
    for (int k = 0; k < 10 * 3; ++k) bvh += " 0";
    bvh += "\n";
  }
  const std::filesystem::path path = std::filesystem::path(::testing::TempDir()) / "z_up.bvh";
  std::ofstream(path) << bvh;
  const auto s = server::session_from_file(path.string(), "z up");
  const core::Model& m = s->model();
  core::Data d(m);
  std::vector<Vector3> hips;
  for (const Eigen::VectorXd& q : s->clip()->frames) {
    core::forward_kinematics(m, d, q);
    const Vector3 up = link_at(m, d, "Head") - link_at(m, d, "Hips");
    EXPECT_GT(up.y(), 0.0);
    EXPECT_NEAR(up.x(), 0.0, 1e-9);
    EXPECT_NEAR(up.z(), 0.0, 1e-9);
    EXPECT_GT(hips_left(m, d).x(), 0.0);
    EXPECT_NEAR(toes_angle_from_plus_z(m, q), 0.0, 1e-6);
    double lowest = core::kInfinity;
    for (int i = 1; i < m.njoints; ++i) lowest = std::min(lowest, d.X_W[i].p.y());
    EXPECT_GE(lowest, 0.0);  // the lowest origin above the floor by less than a capsule
    EXPECT_LT(lowest, 0.1 * up.norm());
    hips.push_back(link_at(m, d, "Hips"));
  }
  EXPECT_GT(hips[1].z() - hips[0].z(), 0.0);
  EXPECT_NEAR(hips[1].x() - hips[0].x(), 0.0, 1e-9);
  EXPECT_NEAR(hips[1].y() - hips[0].y(), 0.0, 1e-9);
}

// CesiumMan's bones are named nodes[N]: its toes tell which way it faces (+X in its file). It
// opens facing +Z, as its knees say: ahead of its hips in its rest pose.
TEST(OpenedPlacement, ANamelessRigOpensFacingWhereItsToesPoint) {
  PINDRAG_REQUIRE_DATA_DIR();
  const auto s = server::session_from_file(fixtures::data_dir() + "/gltf/CesiumMan.glb", "cesium");
  const core::Model& m = s->model();
  core::Data d(m);
  core::forward_kinematics(m, d, core::rest_configuration(m));
  // hips nodes[3] and nodes[7], knees nodes[4] and nodes[8]
  const auto at = [&](const char* name) { return d.X_W[m.link_index(name)].p; };
  const Vector3 knees_ahead = at("nodes[4]") + at("nodes[8]") - at("nodes[3]") - at("nodes[7]");
  const double degrees = std::atan2(knees_ahead.x(), knees_ahead.z()) * 180 / std::numbers::pi;
  EXPECT_LT(std::abs(degrees), 20.0) << knees_ahead.transpose();
  EXPECT_GT(knees_ahead.z(), 0.05);
}

}  // namespace
