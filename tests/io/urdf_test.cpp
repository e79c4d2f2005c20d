// Tests for io/urdf.hpp and io/model_file.hpp: frame conversion, joint and root
// handling, warnings for what is not imported, mesh resolution, every URDF of the shared data and
// benchmark folders, Jacobians against finite differences, a corpus of malformed files, and the
// XML limits (with io/xml_prescan.hpp, what the XML parsers would build).
#include "io/urdf.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "io/character_json.hpp"
#include "io/model_file.hpp"
#include "io/xml_prescan.hpp"
#include "tests/fixtures/fixtures.hpp"
#include "tests/fixtures/kinematics_checks.hpp"

namespace {

namespace fs = std::filesystem;
using core::Geometry;
using core::JointType;
using core::Matrix3;
using core::ModelError;
using core::Transform;
using core::Vector3;
using io::LoadOptions;
using io::LoadResult;
using io::RootJoint;

constexpr double kTol = 1e-12;

// URDF rotation from roll, pitch, yaw about fixed axes: R = Rz(yaw) Ry(pitch) Rx(roll)
// (URDF specification, <origin rpy>)
Matrix3 rpy(double r, double p, double y) {
  return (Eigen::AngleAxisd(y, Vector3::UnitZ()) * Eigen::AngleAxisd(p, Vector3::UnitY()) *
          Eigen::AngleAxisd(r, Vector3::UnitX()))
      .toRotationMatrix();
}

Matrix3 C() { return io::urdf_to_y_up(); }

std::string robot(const std::string& body) {
  return "<?xml version=\"1.0\"?>\n<robot name=\"test\">\n" + body + "\n</robot>\n";
}

LoadResult load(const std::string& xml, LoadOptions options = {}) {
  return io::load_urdf_string(xml, "test.urdf", "", options);
}

// message of the ModelError thrown by f, or "" when nothing was thrown
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

int count_containing(const std::vector<std::string>& lines, const std::string& fragment) {
  return static_cast<int>(std::count_if(lines.begin(), lines.end(), [&](const std::string& l) {
    return l.find(fragment) != std::string::npos;
  }));
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += l + "\n";
  return out;
}

// a fresh folder under the system temp folder, removed at the end of the test
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    path_ = fs::temp_directory_path() /
            ("pindrag_urdf_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
    path_ = fs::canonical(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

void write_file(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

std::vector<std::string> urdf_files_under(const std::string& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().extension() == ".urdf") out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// ------------------------------------------------------------------------------------------------
// frames: Z-up → Y-up

TEST(UrdfFrames, ChangeOfBasisMapsForwardLeftUpToZXY) {
  const Matrix3 c = C();
  EXPECT_TRUE((c * Vector3::UnitX()).isApprox(Vector3::UnitZ()));  // ROS forward → our +Z
  EXPECT_TRUE((c * Vector3::UnitY()).isApprox(Vector3::UnitX()));  // ROS left → our +X
  EXPECT_TRUE((c * Vector3::UnitZ()).isApprox(Vector3::UnitY()));  // ROS up → our +Y
  EXPECT_DOUBLE_EQ(c.determinant(), 1.0);
}

TEST(UrdfFrames, PlacementAxisInertiaAndShapesAreReexpressed) {
  const LoadResult r = load(robot(R"(
  <link name="base">
    <inertial>
      <origin xyz="0.1 -0.2 0.3" rpy="0.3 -0.4 0.5"/>
      <mass value="2.5"/>
      <inertia ixx="0.3" ixy="0.01" ixz="-0.02" iyy="0.25" iyz="0.03" izz="0.2"/>
    </inertial>
    <visual>
      <origin xyz="0.01 0.02 0.03" rpy="0.1 0.2 0.3"/>
      <geometry><box size="0.1 0.2 0.3"/></geometry>
    </visual>
    <collision>
      <origin xyz="0 0 0.1" rpy="1.5707963267948966 0 0"/>
      <geometry><cylinder radius="0.05" length="0.4"/></geometry>
    </collision>
  </link>
  <link name="arm"/>
  <joint name="shoulder" type="revolute">
    <origin xyz="0.4 0.5 0.6" rpy="-0.7 0.2 1.1"/>
    <parent link="base"/><child link="arm"/>
    <axis xyz="0 0.6 0.8"/>
    <limit lower="-1" upper="2" effort="30" velocity="4"/>
  </joint>)"));
  const core::Model& m = *r.model;
  ASSERT_EQ(m.nlinks(), 2);
  const int base = m.link_index("base");
  const int arm = m.link_index("arm");
  ASSERT_EQ(base, 1);
  ASSERT_EQ(arm, 2);

  // joint: X_PJ → (C R Cᵀ, C p), axis → C a
  const Matrix3 R_j = rpy(-0.7, 0.2, 1.1);
  EXPECT_TRUE(m.X_PJ[arm].R.isApprox(C() * R_j * C().transpose(), kTol));
  EXPECT_TRUE(m.X_PJ[arm].p.isApprox(C() * Vector3(0.4, 0.5, 0.6), kTol));
  EXPECT_TRUE(m.axis[arm].isApprox(C() * Vector3(0, 0.6, 0.8), kTol));
  EXPECT_EQ(m.joint_type[arm], JointType::kRevolute);
  EXPECT_EQ(m.joint_name[arm], "shoulder");
  EXPECT_EQ(m.limits[arm], (core::JointLimits{-1, 2, 4, 30}));

  // inertial: COM → C c, inertia about the COM → C R I Rᵀ Cᵀ
  Matrix3 I;
  I << 0.3, 0.01, -0.02, 0.01, 0.25, 0.03, -0.02, 0.03, 0.2;
  const Matrix3 R_i = rpy(0.3, -0.4, 0.5);
  const Matrix3 I_expected = C() * R_i * I * R_i.transpose() * C().transpose();
  EXPECT_DOUBLE_EQ(m.inertia[base].mass, 2.5);
  EXPECT_TRUE(m.inertia[base].com().isApprox(C() * Vector3(0.1, -0.2, 0.3), kTol));
  EXPECT_TRUE(m.inertia[base].inertia_about_com().isApprox(I_expected, 1e-10));

  // shapes: pose → (C R, C p); the shape keeps its own axes and sizes
  ASSERT_EQ(m.visual[base].size(), 1u);
  const Geometry& box = m.visual[base][0];
  EXPECT_EQ(box.shape, Geometry::Shape::kBox);
  EXPECT_TRUE(box.size.isApprox(Vector3(0.1, 0.2, 0.3), kTol));
  EXPECT_TRUE(box.X_LinkShape.R.isApprox(C() * rpy(0.1, 0.2, 0.3), kTol));
  EXPECT_TRUE(box.X_LinkShape.p.isApprox(C() * Vector3(0.01, 0.02, 0.03), kTol));
  ASSERT_EQ(m.collision[base].size(), 1u);
  const Geometry& cyl = m.collision[base][0];
  EXPECT_EQ(cyl.shape, Geometry::Shape::kCylinder);
  EXPECT_DOUBLE_EQ(cyl.radius, 0.05);
  EXPECT_DOUBLE_EQ(cyl.length, 0.4);
  // the URDF cylinder's z axis, turned by roll π/2 to URDF -y, is our -x in the link frame
  EXPECT_TRUE((cyl.X_LinkShape.R * Vector3::UnitZ()).isApprox(Vector3(-1, 0, 0), kTol));
  EXPECT_TRUE(cyl.X_LinkShape.p.isApprox(Vector3(0, 0.1, 0), kTol));
}

TEST(UrdfFrames, WorldPosesAreConjugatedUrdfPoses) {
  // two revolute joints; URDF world poses computed here from the URDF definitions
  const LoadResult r = load(robot(R"(
  <link name="base"/><link name="upper"/><link name="lower"/>
  <joint name="hip" type="revolute">
    <origin xyz="0.1 0.2 0.9" rpy="0.1 0.2 0.3"/><parent link="base"/><child link="upper"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <joint name="knee" type="revolute">
    <origin xyz="0 0 -0.4" rpy="0 0 0"/><parent link="upper"/><child link="lower"/>
    <axis xyz="1 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>)"));
  const core::Model& m = *r.model;
  Eigen::VectorXd q(2);
  q << 0.7, -1.2;
  core::Data data(m);
  core::forward_kinematics(m, data, q);

  const Transform X_base;  // welded at the origin
  const Transform X_upper =
      X_base * Transform{rpy(0.1, 0.2, 0.3), Vector3(0.1, 0.2, 0.9)} *
      Transform::from_rotation(Eigen::AngleAxisd(0.7, Vector3::UnitY()).toRotationMatrix());
  const Transform X_lower =
      X_upper * Transform::from_translation(Vector3(0, 0, -0.4)) *
      Transform::from_rotation(
          Eigen::AngleAxisd(-1.2, Vector3(1, 0, 1).normalized()).toRotationMatrix());
  const std::pair<const char*, Transform> expected[] = {
      {"base", X_base}, {"upper", X_upper}, {"lower", X_lower}};
  for (const auto& [name, X_urdf] : expected) {
    const Transform& X = data.X_W[m.link_index(name)];
    EXPECT_TRUE(X.R.isApprox(C() * X_urdf.R * C().transpose(), kTol)) << name;
    EXPECT_TRUE(X.p.isApprox(C() * X_urdf.p, kTol)) << name;
  }
  // the hip sits 0.9 m above the base (URDF z) and 0.1 m in front (URDF x): our +Y and +Z
  EXPECT_NEAR(data.X_W[m.link_index("upper")].p.y(), 0.9, kTol);
  EXPECT_NEAR(data.X_W[m.link_index("upper")].p.z(), 0.1, kTol);
  EXPECT_NEAR(data.X_W[m.link_index("upper")].p.x(), 0.2, kTol);
  EXPECT_DOUBLE_EQ(m.gravity.y(), -9.81);
}

// ------------------------------------------------------------------------------------------------
// joints and root

TEST(UrdfJoints, EveryTypeMapsToOurs) {
  const LoadResult r = load(robot(R"(
  <link name="base"/><link name="wheel"/><link name="slider"/><link name="bolt"/><link name="prop"/>
  <joint name="spin" type="continuous"><parent link="base"/><child link="wheel"/>
    <axis xyz="0 0 1"/><limit effort="5" velocity="7"/></joint>
  <joint name="slide" type="prismatic"><parent link="base"/><child link="slider"/>
    <axis xyz="1 0 0"/><limit lower="-0.1" upper="0.2" effort="50" velocity="0.5"/></joint>
  <joint name="weld" type="fixed"><origin xyz="0 0 1"/>)"
                                  R"(<parent link="base"/><child link="bolt"/></joint>
  <joint name="thrown" type="floating"><parent link="bolt"/><child link="prop"/></joint>)"));
  const core::Model& m = *r.model;
  const int wheel = m.link_index("wheel"), slider = m.link_index("slider");
  const int bolt = m.link_index("bolt"), prop = m.link_index("prop");
  EXPECT_EQ(m.joint_type[wheel], JointType::kRevolute);
  EXPECT_EQ(m.limits[wheel].lower, -core::kInfinity);
  EXPECT_EQ(m.limits[wheel].upper, core::kInfinity);
  EXPECT_EQ(m.limits[wheel].velocity, 7);
  EXPECT_EQ(m.limits[wheel].effort, 5);
  EXPECT_TRUE(m.axis[wheel].isApprox(Vector3::UnitY()));  // URDF z is our y
  EXPECT_EQ(m.joint_type[slider], JointType::kPrismatic);
  EXPECT_EQ(m.limits[slider], (core::JointLimits{-0.1, 0.2, 0.5, 50}));
  EXPECT_TRUE(m.axis[slider].isApprox(Vector3::UnitZ()));  // URDF x is our z
  EXPECT_EQ(m.joint_type[bolt], JointType::kFixed);
  EXPECT_TRUE(m.X_PJ[bolt].p.isApprox(Vector3(0, 1, 0)));
  EXPECT_EQ(m.joint_type[prop], JointType::kFree);
  EXPECT_EQ(m.nv, 1 + 1 + 6);
  EXPECT_EQ(m.nq, 1 + 1 + 7);
}

TEST(UrdfJoints, PlanarAndUnknownTypesAreRefused) {
  const std::string planar = error_of([] {
    load(robot(R"(<link name="a"/><link name="b"/>
      <joint name="table" type="planar"><parent link="a"/><child link="b"/></joint>)"));
  });
  EXPECT_NE(planar.find("test.urdf: joint 'table': type 'planar' is not supported"),
            std::string::npos)
      << planar;
  EXPECT_NE(
      planar.find("rule: joint types are revolute, continuous, prismatic, fixed and floating"),
      std::string::npos);
  const std::string ball = error_of([] {
    load(robot(R"(<link name="a"/><link name="b"/>
      <joint name="shoulder" type="ball"><parent link="a"/><child link="b"/></joint>)"));
  });
  EXPECT_NE(ball.find("test.urdf: urdfdom: Joint [shoulder] has no known type [ball]"),
            std::string::npos)
      << ball;
}

TEST(UrdfJoints, LockedRangeIsWarned) {
  const LoadResult r = load(robot(R"(<link name="a"/><link name="b"/>
    <joint name="stuck" type="revolute"><parent link="a"/><child link="b"/>
      <limit lower="0" upper="0" effort="1" velocity="1"/></joint>)"));
  EXPECT_EQ(count_containing(r.warnings, "joint 'stuck': lower = upper = 0"), 1)
      << joined(r.warnings);
}

const char* kTwoLinks = R"(
  <link name="pelvis"><inertial><mass value="3"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <link name="thigh"/>
  <joint name="hip" type="continuous"><parent link="pelvis"/><child link="thigh"/></joint>)";

TEST(UrdfRoot, FileRootIsWeldedOrFreedByTheOptions) {
  for (RootJoint root : {RootJoint::kAsInFile, RootJoint::kFixed, RootJoint::kFree}) {
    const LoadResult r = load(robot(kTwoLinks), LoadOptions{root});
    const core::Model& m = *r.model;
    ASSERT_EQ(m.nlinks(), 2);
    EXPECT_EQ(m.link_name[1], "pelvis");
    EXPECT_EQ(m.parent[1], 0);
    EXPECT_EQ(m.joint_name[1], "pelvis");  // URDF has no root joint: named after the link
    EXPECT_EQ(m.joint_type[1], root == RootJoint::kFree ? JointType::kFree : JointType::kFixed);
    EXPECT_EQ(m.nv, root == RootJoint::kFree ? 7 : 1);
    EXPECT_TRUE(r.warnings.empty()) << joined(r.warnings);
  }
}

TEST(UrdfRoot, SyntheticRootJointNameAvoidsExistingJoints) {
  const LoadResult r = load(robot(R"(<link name="base"/><link name="arm"/>
    <joint name="base" type="continuous"><parent link="base"/><child link="arm"/></joint>)"));
  EXPECT_EQ(r.model->joint_name[1], "base_root");
  EXPECT_EQ(r.model->joint_name[2], "base");
}

const char* kWorldFloating = R"(
  <link name="world"/>
  <joint name="float" type="floating"><origin xyz="0 0 1"/>
    <parent link="world"/><child link="pelvis"/></joint>)";

TEST(UrdfRoot, MasslessWorldLinkIsTheWorldAndItsJointTheRootJoint) {
  const LoadResult r = load(robot(std::string(kWorldFloating) + kTwoLinks));
  const core::Model& m = *r.model;
  ASSERT_EQ(m.nlinks(), 2);  // 'world' is not a link of ours
  EXPECT_EQ(m.link_index("world"), -1);
  EXPECT_EQ(m.link_name[1], "pelvis");
  EXPECT_EQ(m.joint_name[1], "float");
  EXPECT_EQ(m.joint_type[1], JointType::kFree);
  EXPECT_TRUE(m.X_PJ[1].p.isApprox(Vector3(0, 1, 0)));  // 1 m up, in Y
  EXPECT_EQ(m.nv, 7);

  // fixed: the world joint is welded where it stands, with a warning naming it
  const LoadResult fixed =
      load(robot(std::string(kWorldFloating) + kTwoLinks), LoadOptions{RootJoint::kFixed});
  EXPECT_EQ(fixed.model->joint_type[1], JointType::kFixed);
  EXPECT_TRUE(fixed.model->X_PJ[1].p.isApprox(Vector3(0, 1, 0)));
  EXPECT_EQ(count_containing(fixed.warnings,
                             "joint 'float' (free) between 'world' and 'pelvis' is replaced by a "
                             "fixed joint"),
            1)
      << joined(fixed.warnings);
}

TEST(UrdfRoot, WorldWithFixedJointIsWeldedAtItsOrigin) {
  const LoadResult r = load(robot(R"(<link name="world"/>
    <joint name="mount" type="fixed"><origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/>
      <parent link="world"/><child link="pelvis"/></joint>)" +
                                  std::string(kTwoLinks)));
  const core::Model& m = *r.model;
  EXPECT_EQ(m.joint_name[1], "mount");
  EXPECT_EQ(m.joint_type[1], JointType::kFixed);
  EXPECT_TRUE(m.X_PJ[1].p.isApprox(Vector3(0, 0, 1)));  // URDF forward is our +Z
  const LoadResult freed = load(robot(R"(<link name="world"/>
    <joint name="mount" type="fixed"><parent link="world"/><child link="pelvis"/></joint>)" +
                                      std::string(kTwoLinks)),
                                LoadOptions{RootJoint::kFree});
  EXPECT_EQ(freed.model->joint_type[1], JointType::kFree);
  EXPECT_EQ(count_containing(freed.warnings,
                             "joint 'mount' (fixed) between 'world' and 'pelvis' "
                             "is replaced by a free joint"),
            1);
}

TEST(UrdfRoot, MassiveWorldLinkIsAnOrdinaryLink) {
  const LoadResult r = load(robot(R"(<link name="world"><inertial><mass value="1"/>
      <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
    <link name="arm"/>
    <joint name="j" type="continuous"><parent link="world"/><child link="arm"/></joint>)"));
  EXPECT_EQ(r.model->nlinks(), 2);
  EXPECT_EQ(r.model->link_index("world"), 1);
}

// ------------------------------------------------------------------------------------------------
// what is not imported is named

TEST(UrdfWarnings, UnsupportedElementsAreNamed) {
  const LoadResult r =
      load(robot(R"(
  <link name="base">
    <visual><geometry><box size="1 1 1"/></geometry><material name="red"/></visual>
    <visual><geometry><cone radius="1" height="2"/></geometry></visual>
    <collision><origin xyz="0 0 0.5"/>)"
                 R"(<geometry><capsule radius="0.1" length="0.3"/></geometry></collision>
    <collision><geometry><sphere radius="0.2"/></geometry></collision>
    <sensor_plate/>
  </link>
  <link name="l_finger1"/><link name="l_finger2"/>
  <joint name="l_finger1" type="revolute"><parent link="base"/><child link="l_finger1"/>
    <limit lower="0" upper="1" effort="1" velocity="1"/>
    <dynamics damping="0.5" friction="0.1"/>
    <safety_controller soft_lower_limit="0" soft_upper_limit="1" k_position="1" k_velocity="1"/>
    <calibration rising="0.1"/>
  </joint>
  <joint name="l_finger2" type="revolute"><parent link="l_finger1"/><child link="l_finger2"/>
    <limit lower="0" upper="1" effort="1" velocity="1"/>
    <mimic joint="l_finger1" multiplier="2" offset="0.1"/>
  </joint>
  <transmission name="t1"/><transmission name="t2"/>
  <gazebo reference="base"/>)"));
  const std::vector<std::string>& w = r.warnings;
  const std::pair<const char*, int> expected[] = {
      {"test.urdf: joint 'l_finger2': mimic of 'l_finger1' (multiplier 2, offset 0.1) is not "
       "supported; the joint moves independently",
       1},
      {"test.urdf: joint 'l_finger1': <dynamics damping friction> is ignored", 1},
      {"test.urdf: joint 'l_finger1': <safety_controller soft_lower_limit soft_upper_limit "
       "k_position k_velocity> is ignored",
       1},
      {"test.urdf: joint 'l_finger1': <calibration rising> is ignored", 1},
      {"test.urdf: <transmission> elements are ignored (2 found", 1},
      {"test.urdf: <gazebo> elements are ignored (1 found", 1},
      {"link 'base': visual (line 6): geometry <cone> is not supported", 1},
      {"link 'base': collision (line 7): <capsule radius=\"0.1\" length=\"0.3\"> is a "
       "non-standard Bullet extension; read as a capsule",
       1},
      {"link 'base': <sensor_plate> (line 9) is not supported and is ignored", 1},
      {"1 <material> elements are ignored", 1},
      {"test.urdf: urdfdom: link 'base' material 'red' undefined.", 1},  // urdfdom's own warning
  };
  for (const auto& [fragment, n] : expected) {
    EXPECT_EQ(count_containing(w, fragment), n) << fragment << "\n" << joined(w);
  }
  EXPECT_EQ(w.size(), std::size(expected)) << joined(w);

  // the cone is gone, the capsule is a capsule, the sphere survives in order
  const core::Model& m = *r.model;
  const int base = m.link_index("base");
  ASSERT_EQ(m.visual[base].size(), 1u);
  EXPECT_EQ(m.visual[base][0].shape, Geometry::Shape::kBox);
  ASSERT_EQ(m.collision[base].size(), 2u);
  EXPECT_EQ(m.collision[base][0].shape, Geometry::Shape::kCapsule);
  EXPECT_DOUBLE_EQ(m.collision[base][0].radius, 0.1);
  EXPECT_DOUBLE_EQ(m.collision[base][0].length, 0.3);
  EXPECT_TRUE(m.collision[base][0].X_LinkShape.p.isApprox(Vector3(0, 0.5, 0)));
  EXPECT_EQ(m.collision[base][1].shape, Geometry::Shape::kSphere);
  EXPECT_EQ(m.nv, 2);  // the mimic joint moves on its own
}

TEST(UrdfWarnings, ManyWarningsAreCountedNotListed) {
  std::string body = "<link name=\"a\">";
  for (int i = 0; i < 1500; ++i) body += "<extra" + std::to_string(i) + "/>";
  body += "</link>";
  const LoadResult r = load(robot(body));
  ASSERT_EQ(r.warnings.size(), io::kMaxUrdfWarnings);
  EXPECT_EQ(r.warnings.front(),
            "test.urdf: link 'a': <extra0> (line 3) is not supported and is ignored");
  EXPECT_EQ(r.warnings.back(), "test.urdf: " + std::to_string(1500 - (io::kMaxUrdfWarnings - 1)) +
                                   " more warnings are not listed");
}

TEST(UrdfWarnings, UrdfdomErrorsAreFatalAndCarryItsMessage) {
  // urdfdom drops an unreadable inertial and goes on; we refuse instead of losing the mass
  const std::string e = error_of([] {
    load(robot(R"(<link name="a"><inertial><mass value="0x10"/>
      <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>)"));
  });
  EXPECT_NE(e.find("test.urdf: urdfdom: Inertial: mass [0x10] is not a float"), std::string::npos)
      << e;
  EXPECT_NE(e.find("test.urdf: urdfdom: Could not parse inertial element for Link [a]"),
            std::string::npos);
  EXPECT_NE(e.find("rule: the file must be valid URDF"), std::string::npos);
}

// ------------------------------------------------------------------------------------------------
// meshes

std::string mesh_link(const std::string& name, const std::string& uri, const char* extra = "") {
  return "<link name=\"" + name + "\"><visual><geometry><mesh filename=\"" + uri + "\"" + extra +
         "/></geometry></visual></link>\n";
}

std::string fixed_joints(const std::vector<std::string>& children) {
  std::string out;
  for (const std::string& c : children) {
    out += "<joint name=\"to_" + c + "\" type=\"fixed\"><parent link=\"root\"/><child link=\"" + c +
           "\"/></joint>\n";
  }
  return out;
}

TEST(UrdfMeshes, PackageRelativeFileAndEscapes) {
  TempDir tmp;
  const fs::path pkg = tmp.path() / "ws" / "my_robot";
  write_file(pkg / "meshes" / "body.stl", "solid body\nendsolid body\n");
  write_file(pkg / "meshes" / "sub" / "hand.stl", "solid hand\nendsolid hand\n");
  write_file(tmp.path() / "ws" / "outside.stl", "solid outside\nendsolid outside\n");
  fs::create_directories(tmp.path() / "other_pkg" / "meshes");
  write_file(tmp.path() / "other_pkg" / "meshes" / "x.stl", "solid x\nendsolid x\n");
  fs::create_symlink(tmp.path() / "ws" / "outside.stl", pkg / "meshes" / "sneaky.stl");

  const std::vector<std::pair<std::string, std::string>> links = {
      {"package", "package://my_robot/meshes/body.stl"},
      {"relative", "../meshes/sub/hand.stl"},
      {"file_uri", "file://" + (pkg / "meshes" / "body.stl").string()},
      {"absolute_inside", (pkg / "meshes" / "sub" / "hand.stl").string()},
      {"absolute_outside", (tmp.path() / "ws" / "outside.stl").string()},
      {"dotdot", "package://my_robot/../outside.stl"},
      {"symlink", "package://my_robot/meshes/sneaky.stl"},
      {"other_package", "package://other_pkg/meshes/x.stl"},
      {"missing", "package://my_robot/meshes/missing.stl"},
      {"http", "http://example.com/body.stl"},
  };
  std::string body = "<link name=\"root\"/>\n";
  std::vector<std::string> names;
  for (const auto& [name, uri] : links) {
    body += mesh_link(name, uri, name == "package" ? " scale=\"0.001 0.002 0.003\"" : "");
    names.push_back(name);
  }
  body += fixed_joints(names);
  const fs::path urdf = pkg / "urdf" / "robot.urdf";
  write_file(urdf, robot(body));

  const LoadResult r = io::load_urdf_file(urdf.string());
  const core::Model& m = *r.model;
  EXPECT_EQ(m.source_dir, pkg.string());  // the package folder is the model folder
  auto mesh_of = [&](const std::string& link) -> std::string {
    const auto& v = m.visual[m.link_index(link)];
    return v.empty() ? "<dropped>" : v[0].mesh;
  };
  EXPECT_EQ(mesh_of("package"), "meshes/body.stl");
  EXPECT_TRUE(m.visual[m.link_index("package")][0].scale.isApprox(Vector3(0.001, 0.002, 0.003)));
  EXPECT_EQ(mesh_of("relative"), "meshes/sub/hand.stl");
  EXPECT_EQ(mesh_of("file_uri"), "meshes/body.stl");
  EXPECT_EQ(mesh_of("absolute_inside"), "meshes/sub/hand.stl");
  for (const char* dropped :
       {"absolute_outside", "dotdot", "symlink", "other_package", "missing", "http"}) {
    EXPECT_EQ(mesh_of(dropped), "<dropped>") << dropped;
  }
  const std::string prefix = urdf.string() + ": link '";
  const std::pair<std::string, std::string> expected[] = {
      {"absolute_outside", "resolves to " + (tmp.path() / "ws" / "outside.stl").string() +
                               ", outside the model folder (rule: meshes must lie inside the "
                               "model folder " +
                               pkg.string() + "); refused"},
      {"dotdot", "resolves to " + (tmp.path() / "ws" / "outside.stl").string() +
                     ", outside the model folder"},
      {"symlink", "resolves through a symbolic link to " +
                      (tmp.path() / "ws" / "outside.stl").string() + ", outside the model folder"},
      {"other_package",
       "names package 'other_pkg', but no folder of that name contains " + (pkg / "urdf").string()},
      {"missing", "was not found (looked for " + (pkg / "meshes" / "missing.stl").string() + ")"},
      {"http", "uses the URI scheme 'http', which is not supported"},
  };
  for (const auto& [link, fragment] : expected) {
    const auto uri = std::find_if(links.begin(), links.end(),
                                  [name = link](const auto& l) { return l.first == name; });
    const std::string head = prefix + link + "': visual mesh '" + uri->second + "' ";
    ASSERT_EQ(count_containing(r.warnings, head), 1) << head << "\n" << joined(r.warnings);
    for (const std::string& w : r.warnings) {
      if (w.rfind(head, 0) != 0) continue;
      EXPECT_NE(w.find(fragment), std::string::npos) << w;
      EXPECT_NE(w.find("; shape dropped"), std::string::npos) << w;
    }
  }
  EXPECT_EQ(r.warnings.size(), std::size(expected)) << joined(r.warnings);
  for (const auto& v : m.visual) {
    for (const Geometry& g : v) {
      EXPECT_EQ(g.mesh.find(".."), std::string::npos) << g.mesh;
      EXPECT_TRUE(fs::is_regular_file(fs::path(m.source_dir) / g.mesh)) << g.mesh;
    }
  }
}

TEST(UrdfMeshes, WithoutPackageTheUrdfFolderIsTheModelFolder) {
  TempDir tmp;
  write_file(tmp.path() / "robot" / "meshes" / "a.stl", "solid a\nendsolid a\n");
  write_file(tmp.path() / "secret.stl", "solid s\nendsolid s\n");
  const fs::path urdf = tmp.path() / "robot" / "robot.urdf";
  write_file(urdf, robot("<link name=\"root\"/>" + mesh_link("a", "meshes/a.stl") +
                         mesh_link("up", "../secret.stl") + fixed_joints({"a", "up"})));
  const LoadResult r = io::load_urdf_file(urdf.string());
  EXPECT_EQ(r.model->source_dir, (tmp.path() / "robot").string());
  EXPECT_EQ(r.model->visual[r.model->link_index("a")][0].mesh, "meshes/a.stl");
  EXPECT_TRUE(r.model->visual[r.model->link_index("up")].empty());
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("link 'up': visual mesh '../secret.stl' resolves to " +
                               (tmp.path() / "secret.stl").string() + ", outside the model folder"),
            std::string::npos)
      << r.warnings[0];
}

TEST(UrdfMeshes, TextWithoutBaseFolderDropsMeshesWithAWarning) {
  const LoadResult r = load(robot(mesh_link("a", "meshes/a.stl")));
  EXPECT_TRUE(r.model->visual[1].empty());
  EXPECT_TRUE(r.model->source_dir.empty());
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("test.urdf: link 'a': visual mesh 'meshes/a.stl' cannot be "
                               "resolved: no model folder was given"),
            std::string::npos)
      << r.warnings[0];
}

// ------------------------------------------------------------------------------------------------
// the shared data and benchmark URDFs

struct SharedUrdf {
  const char* file;  // relative to data_dir()/urdf
  int nlinks;
  int nv;
  std::vector<std::pair<std::string, int>> warnings;  // fragment, how many warnings contain it
  std::string source_dir_suffix;                      // Model::source_dir ends with this
  int meshes;                                         // mesh shapes kept (visual + collision)
  int capsules;
};

const std::vector<SharedUrdf>& shared_urdfs() {
  static const std::vector<SharedUrdf> files = {
      {"unitree_h1.urdf",
       25,
       19,
       {{"names package 'h1_description', but no folder of that name contains", 21},
        {"<mujoco> elements are ignored (1 found", 1},
        {"24 <material> elements are ignored", 1}},
       "data/urdf",
       0,
       0},
      {"unitree_g1_29dof_with_hand.urdf",
       54,
       43,
       {{"' was not found (looked for ", 89}, {"<mujoco> elements are ignored (1 found", 1}},
       "data/urdf",
       0,
       0},
      {"jvrc_description/urdf/jvrc1.urdf",
       60,
       44,
       {{"is not supported; the joint moves independently", 10},
        {"joint 'R_LTHUMB': mimic of 'R_UTHUMB' (multiplier 3, offset 0) is not supported", 1},
        {"<sensor> elements are ignored (10 found", 1}},
       "data/urdf/jvrc_description",
       70,
       0},
      {"bullet_humanoid_capsules.urdf",
       34,
       21,
       {{"is a non-standard Bullet extension; read as a capsule", 16},
        {"<dynamics damping friction> is ignored", 33}},
       "data/urdf",
       0,
       16},
  };
  return files;
}

TEST(UrdfSharedData, EveryUrdfLoadsOrIsRefusedWithTheReason) {
  PINDRAG_REQUIRE_DATA_DIR();
  const std::string dir = fixtures::data_dir() + "/urdf";
  if (!fs::is_directory(dir)) GTEST_SKIP() << dir << " is absent";
  const std::vector<std::string> files = urdf_files_under(dir);
  ASSERT_FALSE(files.empty());
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    const auto known = std::find_if(shared_urdfs().begin(), shared_urdfs().end(), [&](auto& s) {
      return fs::equivalent(path, dir + "/" + s.file);
    });
    try {
      const LoadResult r = io::load_model_file(path);
      for (const std::string& w : r.warnings) EXPECT_EQ(w.rfind(path + ": ", 0), 0u) << w;
      if (known == shared_urdfs().end()) continue;  // a new file: loading is enough
      const core::Model& m = *r.model;
      EXPECT_EQ(m.nlinks(), known->nlinks);
      EXPECT_EQ(m.nv, known->nv);
      int meshes = 0, capsules = 0;
      for (int i = 1; i < m.njoints; ++i) {
        for (const auto* shapes : {&m.visual[i], &m.collision[i]}) {
          for (const Geometry& g : *shapes) {
            meshes += g.shape == Geometry::Shape::kMesh;
            capsules += g.shape == Geometry::Shape::kCapsule;
            if (g.shape == Geometry::Shape::kMesh) {
              EXPECT_TRUE(fs::is_regular_file(fs::path(m.source_dir) / g.mesh)) << g.mesh;
            }
          }
        }
      }
      EXPECT_EQ(meshes, known->meshes);
      EXPECT_EQ(capsules, known->capsules);
      for (const auto& [fragment, n] : known->warnings) {
        EXPECT_EQ(count_containing(r.warnings, fragment), n) << fragment;
      }
      const std::string suffix = known->source_dir_suffix;
      EXPECT_EQ(
          m.source_dir.substr(m.source_dir.size() - std::min(m.source_dir.size(), suffix.size())),
          suffix);
      EXPECT_EQ(m.joint_type[1], JointType::kFixed);  // URDF roots are welded unless asked
    } catch (const ModelError& e) {
      // only new files may be refused, and then with the file and the rule named
      const std::string what = e.what();
      EXPECT_EQ(known, shared_urdfs().end()) << "a known file was refused: " << what;
      EXPECT_NE(what.find(path + ": "), std::string::npos) << what;
      EXPECT_NE(what.find("rule"), std::string::npos) << what;
    }
  }
  for (const SharedUrdf& s : shared_urdfs()) {
    EXPECT_TRUE(fs::is_regular_file(dir + "/" + s.file)) << s.file << " is missing";
  }
}

TEST(UrdfSharedData, BenchmarkModelsLoad) {
  PINDRAG_REQUIRE_BENCH_DIR();
  const std::string dir = fixtures::bench_models_dir();
  const std::vector<std::string> files = urdf_files_under(dir);
  ASSERT_FALSE(files.empty());
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    const std::string stem = fs::path(path).stem().string();
    const LoadResult r = io::load_urdf_file(path);
    EXPECT_TRUE(r.warnings.empty()) << joined(r.warnings);
    const core::Model& m = *r.model;
    if (stem.rfind("chain", 0) == 0) {
      const int n = std::stoi(stem.substr(5));
      EXPECT_EQ(m.nv, n);
      EXPECT_EQ(m.nlinks(), n + 1);
    } else if (stem.find("_float6") != std::string::npos) {
      // a massless 'world' root: its joint (prismatic along URDF x) is our root joint
      EXPECT_EQ(m.link_index("world"), -1);
      EXPECT_EQ(m.joint_name[1], "j01_base_tx");
      EXPECT_EQ(m.joint_type[1], JointType::kPrismatic);
      EXPECT_TRUE(m.axis[1].isApprox(Vector3::UnitZ()));
      EXPECT_EQ(m.nv, stem == "human48_float6" ? 48 : 34);
    }
  }
}

TEST(UrdfSharedData, Human48LoadsFreeAndFixed) {
  PINDRAG_REQUIRE_BENCH_DIR();
  const std::string path = fixtures::bench_models_dir() + "/human48.urdf";
  if (!fs::is_regular_file(path)) GTEST_SKIP() << path << " is absent";
  const LoadResult free_root = io::load_urdf_file(path, LoadOptions{RootJoint::kFree});
  EXPECT_EQ(free_root.model->nv, 48);
  EXPECT_EQ(free_root.model->nq, 49);
  EXPECT_EQ(free_root.model->joint_type[1], JointType::kFree);
  EXPECT_EQ(free_root.model->link_name[1], "pelvis");
  const LoadResult fixed = io::load_urdf_file(path, LoadOptions{RootJoint::kFixed});
  EXPECT_EQ(fixed.model->nv, 42);
  EXPECT_EQ(fixed.model->joint_type[1], JointType::kFixed);
  EXPECT_EQ(fixed.model->nlinks(), free_root.model->nlinks());
  EXPECT_NEAR(fixed.model->total_mass(), 75.0, 0.5);  // de Leva, 75 kg male
  const LoadResult as_in_file = io::load_urdf_file(path);
  EXPECT_EQ(*as_in_file.model, *fixed.model);
}

// ------------------------------------------------------------------------------------------------
// Jacobians of every loadable URDF against finite differences

std::vector<std::pair<std::string, LoadOptions>> loadable_urdfs() {
  std::vector<std::pair<std::string, LoadOptions>> out;
  if (!fixtures::data_dir().empty() && fs::is_directory(fixtures::data_dir() + "/urdf")) {
    for (const std::string& p : urdf_files_under(fixtures::data_dir() + "/urdf")) {
      out.push_back({p, LoadOptions{RootJoint::kFree}});  // a free root exercises the free joint
    }
  }
  if (!fixtures::bench_models_dir().empty()) {
    for (const std::string& p : urdf_files_under(fixtures::bench_models_dir())) {
      const bool human = fs::path(p).stem().string().rfind("human", 0) == 0 &&
                         p.find("_float6") == std::string::npos;
      out.push_back({p, LoadOptions{human ? RootJoint::kFree : RootJoint::kAsInFile}});
    }
  }
  return out;
}

TEST(UrdfKinematics, JacobiansMatchFiniteDifferencesOnEveryUrdf) {
  const auto files = loadable_urdfs();
  if (files.empty()) GTEST_SKIP() << "neither the shared data nor the benchmark folder is present";
  for (const auto& [path, options] : files) {
    SCOPED_TRACE(path);
    const LoadResult r = io::load_urdf_file(path, options);
    const core::Model& m = *r.model;
    // the 512-link chain costs O(n³) per check: one configuration is enough there
    const int seeds = m.nv > 200 ? 1 : 3;
    for (int seed = 1; seed <= seeds; ++seed) {
      const Eigen::VectorXd q = core::random_configuration(m, seed);
      fixtures::expect_jacobians_match_finite_differences(m, q, 1e-7);
      const Eigen::VectorXd v = Eigen::VectorXd::Random(m.nv);
      fixtures::expect_jdot_v_matches_finite_differences(m, q, v, 1e-6);
    }
  }
}

// ------------------------------------------------------------------------------------------------
// malformed files: a ModelError naming the file and the rule, never a crash

std::string malformed_dir() { return fixtures::source_dir() + "/tests/fixtures/malformed/urdf"; }

struct Malformed {
  const char* file;
  std::vector<std::string> fragments;  // each must appear in the message
};

const std::vector<Malformed>& malformed_corpus() {
  static const std::vector<Malformed> corpus = {
      {"truncated.urdf",
       {"not well-formed XML (rule: a URDF is an XML document)", "XML_ERROR_PARSING",
        "urdfdom: Error reading end tag."}},
      {"duplicate_link.urdf",
       {"urdfdom: link 'arm' is not unique.", "rule: the file must be valid URDF"}},
      {"cycle.urdf",
       {"links 'b', 'a' form a cycle through joints 'a_to_b', 'b_to_a' (rule: the links form a "
        "tree, no cycles)"}},
      {"rootless_cycle.urdf",
       {"links 'b', 'a' form a cycle through joints 'a_to_b', 'b_to_a' (rule: the links form a "
        "tree, no cycles)"}},
      {"two_parents.urdf",
       {"link 'arm' is the child of 2 joints 'shoulder' (line 7), 'closure' (line 9) (rule: a "
        "link has at most one parent joint; the links form a tree)"}},
      {"missing_parent.urdf",
       {"urdfdom: Failed to build tree: parent link [ghost] of joint [shoulder] not found",
        "rule: the file must be valid URDF"}},
      {"nan_origin.urdf",
       {"urdfdom: Unable to parse component [NaN] to a double",
        "urdfdom: Malformed parent origin element for joint [shoulder]",
        "rule: the file must be valid URDF"}},
      {"inf_mass.urdf",
       {"urdfdom: Inertial: mass [inf] is not a float",
        "urdfdom: Could not parse inertial element for Link [base]",
        "rule: the file must be valid URDF"}},
      {"inf_limit.urdf",
       {"urdfdom: lower value (-inf) is not a valid float",
        "urdfdom: Could not parse limit element for joint [elbow]"}},
      {"negative_mass.urdf", {"link 'base': mass -2 is negative (rule: mass must be >= 0)"}},
      {"inertia_triangle.urdf",
       {"link 'base': principal moments 0.1, 0.1, 0.5 violate the triangle inequality (rule: I1 + "
        "I2 >= I3)"}},
      {"lower_above_upper.urdf",
       {"joint 'elbow': lower limit 1.5 > upper limit -0.5 (rule: lower <= upper)"}},
      {"planar_joint.urdf",
       {"joint 'table': type 'planar' is not supported (rule: joint types are revolute, "
        "continuous, prismatic, fixed and floating)"}},
      {"unknown_joint_type.urdf", {"urdfdom: Joint [shoulder] has no known type [ball]"}},
      {"empty.urdf",
       {"not well-formed XML (rule: a URDF is an XML document)", "XML_ERROR_EMPTY_DOCUMENT",
        "urdfdom: Error document empty."}},
      {"binary_garbage.urdf", {"not well-formed XML (rule: a URDF is an XML document)"}},
      {"no_robot.urdf",
       {"no <robot> element (rule: a URDF's root element is <robot>)",
        "urdfdom: Could not find the 'robot' element in the xml file"}},
      // a fuzzer's find: tinyxml2 stops at the stray end tag, TinyXML 1 reads on into a rootless
      // cycle that urdfdom would build and never free, so urdfdom is not asked
      {"stray_end_tag_hides_a_cycle.urdf",
       {"no <robot> element (rule: a URDF's root element is <robot>)",
        "urdfdom's XML parser (TinyXML) finds a <robot> element where tinyxml2 finds none"}},
      {"world_two_children.urdf",
       {"link 'world' is a massless root with 2 child joints (rule: the world link connects to "
        "exactly one link, the model's root)"}},
      {"capsule_without_length.urdf",
       {"link 'base': collision (line 4): <capsule> needs radius and length attributes"}},
  };
  return corpus;
}

TEST(UrdfMalformed, EveryFileIsRefusedNamingTheFileAndTheRule) {
  const std::string dir = malformed_dir();
  ASSERT_TRUE(fs::is_directory(dir)) << dir;
  for (const Malformed& c : malformed_corpus()) {
    const std::string path = dir + "/" + c.file;
    SCOPED_TRACE(path);
    ASSERT_TRUE(fs::is_regular_file(path));
    std::vector<std::string> violations;
    try {
      io::load_model_file(path);
      ADD_FAILURE() << "loaded without an error";
      continue;
    } catch (const ModelError& e) {
      violations = e.violations();
    }
    ASSERT_FALSE(violations.empty());
    for (const std::string& v : violations) EXPECT_EQ(v.rfind(path + ": ", 0), 0u) << v;
    const std::string what = joined(violations);
    for (const std::string& f : c.fragments)
      EXPECT_NE(what.find(f), std::string::npos) << f << "\n" << what;
  }
  // every file of the corpus is covered above, except the mesh escape (a warning, below)
  for (const std::string& path : urdf_files_under(dir)) {
    const std::string name = fs::path(path).filename().string();
    const bool covered = name == "mesh_escape.urdf" ||
                         std::any_of(malformed_corpus().begin(), malformed_corpus().end(),
                                     [&](const Malformed& c) { return name == c.file; });
    EXPECT_TRUE(covered) << name << " has no expectation";
  }
}

TEST(UrdfMalformed, EscapingMeshIsRefusedWithAWarningAndDropped) {
  // a mesh outside the model folder is dropped, not fatal: the rest of the model is sound
  const std::string path = malformed_dir() + "/mesh_escape.urdf";
  const LoadResult r = io::load_urdf_file(path);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_EQ(r.warnings[0],
            path +
                ": link 'base': visual mesh '../../../../../../../../../../etc/passwd' "
                "resolves to /etc/passwd, outside the model folder (rule: meshes must lie "
                "inside the model folder " +
                fs::canonical(malformed_dir()).string() + "); refused; shape dropped");
  EXPECT_TRUE(r.model->visual[1].empty());
  ASSERT_EQ(r.model->collision[1].size(), 1u);  // the box beside it is kept
}

TEST(UrdfMalformed, TooManyLinksIsRefusedBeforeBuilding) {
  TempDir tmp;
  const int n = core::kMaxLinks + 1;
  std::string body;
  body.reserve(static_cast<size_t>(n) * 160);
  for (int i = 0; i < n; ++i) body += "<link name=\"l" + std::to_string(i) + "\"/>\n";
  for (int i = 1; i < n; ++i) {
    body += "<joint name=\"j" + std::to_string(i) + "\" type=\"continuous\"><parent link=\"l" +
            std::to_string(i - 1) + "\"/><child link=\"l" + std::to_string(i) + "\"/></joint>\n";
  }
  const fs::path path = tmp.path() / "huge.urdf";
  write_file(path, robot(body));
  const std::string e = error_of([&] { io::load_urdf_file(path.string()); });
  EXPECT_EQ(e, path.string() + ": model has " + std::to_string(n) + " links (rule: at most " +
                   std::to_string(core::kMaxLinks) + " links)");
}

TEST(UrdfMalformed, OversizedTextIsRefusedBeforeParsing) {
  const std::string huge(io::kMaxUrdfBytes + 1, ' ');
  const std::string e = error_of([&] { load(huge); });
  EXPECT_EQ(e, "test.urdf: file is " + std::to_string(huge.size()) +
                   " bytes (rule: a URDF is at most " + std::to_string(io::kMaxUrdfBytes) +
                   " bytes)");
}

TEST(UrdfMalformed, FinalizeErrorsCarryTheFileName) {
  const std::string e = error_of([] {
    load(robot(R"(<link name="a"/><link name="b"/>
      <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 0"/>
        <limit lower="0" upper="1" effort="-1" velocity="1"/></joint>)"));
  });
  EXPECT_NE(e.find("test.urdf: joint 'j': axis must be finite and non-zero"), std::string::npos)
      << e;
  EXPECT_NE(e.find("test.urdf: joint 'j': velocity and effort limits must be >= 0"),
            std::string::npos)
      << e;
}

TEST(UrdfMalformed, OversizedFileIsRefusedBeforeReading) {
  TempDir tmp;
  const fs::path path = tmp.path() / "huge.urdf";
  write_file(path, "");
  fs::resize_file(path, io::kMaxUrdfBytes + 1);  // sparse: nothing of it is read
  EXPECT_EQ(error_of([&] { io::load_urdf_file(path.string()); }),
            path.string() + ": file is " + std::to_string(io::kMaxUrdfBytes + 1) +
                " bytes (rule: a URDF is at most " + std::to_string(io::kMaxUrdfBytes) + " bytes)");
  EXPECT_EQ(error_of([&] { io::load_urdf_file(tmp.path().string()); }),
            tmp.path().string() + ": is not a regular file");
}

TEST(UrdfMalformed, RepeatedJointNameIsRefusedWithTheLineOfEachDefinition) {
  // urdfdom refuses a repeated joint name without saying where; every definition is named
  const std::string twice = robot(R"(<link name="a"/><link name="b"/><link name="c"/>
<joint name="knee" type="fixed"><parent link="a"/><child link="b"/></joint>
<joint name="knee" type="fixed"><parent link="b"/><child link="c"/></joint>)");
  EXPECT_EQ(error_of([&] { load(twice); }),
            "test.urdf: joint 'knee' is defined twice (lines 4 and 5) (rule: joint names are "
            "unique)");
  // the same joint three times: one message, not "the child of 3 joints" as well
  const std::string thrice = robot(R"(<link name="a"/><link name="b"/>
<joint name="hip" type="fixed"><parent link="a"/><child link="b"/></joint>
<joint name="hip" type="fixed"><parent link="a"/><child link="b"/></joint>
<joint name="hip" type="fixed"><parent link="a"/><child link="b"/></joint>)");
  EXPECT_EQ(error_of([&] { load(thrice); }),
            "test.urdf: joint 'hip' is defined 3 times (lines 4, 5 and 6) (rule: joint names are "
            "unique)");
}

TEST(UrdfMalformed, RepeatedLinkNameIsRefused) {
  const std::string e = error_of([] {
    load(robot(R"(<link name="base"/><link name="arm"/>
<link name="arm"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1"/></inertial></link>
<joint name="shoulder" type="fixed"><parent link="base"/><child link="arm"/></joint>)"));
  });
  EXPECT_NE(e.find("test.urdf: urdfdom: link 'arm' is not unique."), std::string::npos) << e;
}

// ------------------------------------------------------------------------------------------------
// element nesting: refused before any XML parser recurses into it

std::string nesting_error(int line) {
  const std::string n = std::to_string(io::kMaxUrdfDepth);
  return "line " + std::to_string(line) + ": elements are nested deeper than " + n +
         " (rule: a URDF nests XML elements at most " + n + " deep)";
}

TEST(UrdfNesting, DeepFilesAreRefusedWithoutCrashing) {
  // 40,000 levels overflowed the stack of urdfdom's recursive XML parser (TinyXML 1)
  TempDir tmp;
  for (int levels : {40000, 1000}) {
    std::string text = "<robot>";
    for (int i = 0; i < levels; ++i) text += "<a>";
    const fs::path path = tmp.path() / ("deep" + std::to_string(levels) + ".urdf");
    write_file(path, text);
    EXPECT_EQ(error_of([&] { io::load_model_file(path.string()); }),
              path.string() + ": " + nesting_error(1));
  }
}

TEST(UrdfNesting, AFileAtTheLimitLoadsAndOneLevelDeeperIsRefused) {
  // <robot> is level 1; ignored <gazebo> elements nest the other levels, one per line
  auto nested = [](int depth) {
    std::string open, close;
    for (int level = 2; level <= depth; ++level) {
      open += "<gazebo>\n";
      close += "</gazebo>\n";
    }
    return "<robot name=\"deep\">\n<link name=\"base\"/>\n" + open + close + "</robot>\n";
  };
  const LoadResult r = load(nested(io::kMaxUrdfDepth));
  EXPECT_EQ(r.model->nlinks(), 1);
  EXPECT_EQ(count_containing(r.warnings, "<gazebo> elements are ignored (1 found"), 1);
  // level L is on line L + 1
  EXPECT_EQ(error_of([&] { load(nested(io::kMaxUrdfDepth + 1)); }),
            "test.urdf: " + nesting_error(io::kMaxUrdfDepth + 2));
}

TEST(UrdfNesting, NestingThatOnlyUrdfdomsParserSeesIsRefused) {
  // tinyxml2 reads both files as two levels deep; TinyXML 1 ends a processing instruction at its
  // first '>', and after a declaration reads UTF-8, where a stray lead byte swallows the end tag
  // after it. Both crashed the loader before the nesting rule.
  std::string instruction = "<?pi ", lead_bytes;
  for (int i = 0; i < 40000; ++i) {
    instruction += "<a>";
    lead_bytes += "<a>\xF0</a>";
  }
  instruction += "?>\n<robot name=\"r\"><link name=\"l\"/></robot>\n";
  EXPECT_EQ(error_of([&] { load(instruction); }), "test.urdf: " + nesting_error(1));
  lead_bytes =
      "<?xml version=\"1.0\"?>\n<robot name=\"r\"><link name=\"l\"/>" + lead_bytes + "</robot>\n";
  EXPECT_EQ(error_of([&] { load(lead_bytes); }), "test.urdf: " + nesting_error(2));
}

TEST(UrdfXmlLimits, ManyAttributesOnOneElementAreRefusedBeforeParsing) {
  // both XML parsers compare each attribute with every earlier one of its element: 200,000 of
  // them took minutes
  auto link = [](int attributes) {
    std::string text = "<robot name=\"r\">\n<link name=\"base\"";
    for (int i = 1; i < attributes; ++i) text += " a" + std::to_string(i) + "=\"1\"";
    return text + "/>\n</robot>\n";
  };
  EXPECT_EQ(load(link(io::kMaxUrdfAttributes)).model->nlinks(), 1);
  const std::string n = std::to_string(io::kMaxUrdfAttributes);
  const std::string refused = "test.urdf: line 2: an element has more than " + n +
                              " attributes (rule: an XML element of a URDF has at most " + n +
                              " attributes)";
  EXPECT_EQ(error_of([&] { load(link(io::kMaxUrdfAttributes + 1)); }), refused);
  EXPECT_EQ(error_of([&] { load(link(200000)); }), refused);
}

// prescan_xml with room for anything but what a test is about
io::XmlPrescan prescan(std::string_view text, int depth = 64, int attributes = 64) {
  return io::prescan_xml(text, {depth, attributes});
}

TEST(XmlPrescan, CountsElementsAsTinyXml1ReadsThem) {
  EXPECT_EQ(prescan("<a><b/><c><d/></c></a>").depth, 3);
  EXPECT_EQ(prescan("").depth, 0);
  // markup in values, comments and CDATA is not an element
  EXPECT_EQ(prescan("<a x=\"<b><b>\"><!-- <c><c> --><![CDATA[<d><d>]]></a>").depth, 1);
  // TinyXML 1's own reading: an instruction ends at its first '>'; "&#x...;" skips to its ';'
  EXPECT_EQ(prescan("<?pi <x><b><c>?>").depth, 2);
  EXPECT_EQ(prescan("<a>&#x</a>x1;<b/></a>").depth, 2);
  // a lead byte hides the end tag in UTF-8 mode: after a declaration or a byte-order mark only
  EXPECT_EQ(prescan("<a>\xF0</a><b/>").depth, 1);
  EXPECT_EQ(prescan("<?xml version=\"1.0\"?><a>\xF0</a><b/>").depth, 2);
  EXPECT_EQ(prescan("\xEF\xBB\xBF<a>\xF0</a><b/>").depth, 2);
  // both parsers read a C string: nothing after the first NUL
  EXPECT_EQ(prescan(std::string_view("<a>\0<b><c>", 10)).depth, 1);
}

TEST(XmlPrescan, CountsAttributesAsEitherParserReadsThem) {
  EXPECT_EQ(prescan("<a x=\"1\" y='2'><b z=\"3\"/></a>").attributes, 2);
  // TinyXML 1 takes unquoted values; tinyxml2 reads attributes in an end tag
  EXPECT_EQ(prescan("<a x=1 y=2 z=3/>").attributes, 3);
  EXPECT_EQ(prescan("<a></a x=\"1\" y=\"2\">").attributes, 2);
  // TinyXML 1 stops at "&#xg;", but tinyxml2 goes on to the element after it
  EXPECT_EQ(prescan("<a x=\"&#xg;\"/><b x=\"1\" y=\"2\" z=\"3\"/>").attributes, 3);
}

TEST(XmlPrescan, StopsAtTheFirstElementBeyondALimitAndNamesItsLine) {
  const io::XmlPrescan deep = prescan("<a>\n<b>\n<c>\n<d>", 2);
  EXPECT_EQ(deep.excess, io::XmlPrescan::Excess::kDepth);
  EXPECT_EQ(deep.depth, 3);
  EXPECT_EQ(deep.line, 3);
  EXPECT_EQ(prescan("<a>\n<b>\n<c>\n<d>", 4).excess, io::XmlPrescan::Excess::kNone);
  EXPECT_EQ(prescan("<a>\n<b>\n<c>\n<d>", 4).line, 0);
  const io::XmlPrescan wide = prescan("<a>\n<b x='1' y='2' z='3'/></a>", 64, 2);
  EXPECT_EQ(wide.excess, io::XmlPrescan::Excess::kAttributes);
  EXPECT_EQ(wide.attributes, 3);
  EXPECT_EQ(wide.line, 2);
}

// ------------------------------------------------------------------------------------------------
// load_model_file

TEST(ModelFile, DispatchesOnTheExtension) {
  TempDir tmp;
  const fs::path urdf = tmp.path() / "Robot.URDF";
  write_file(urdf, robot(kTwoLinks));
  EXPECT_EQ(io::load_model_file(urdf.string()).model->nlinks(), 2);
  const fs::path txt = tmp.path() / "robot.txt";
  write_file(txt, robot(kTwoLinks));
  EXPECT_EQ(error_of([&] { io::load_model_file(txt.string()); }),
            txt.string() +
                ": unknown file type '.txt' (rule: character files end in .urdf or "
                ".json)");
  // .json goes to the character loader: a URDF model written as JSON comes back the same
  const LoadResult from_urdf = io::load_model_file(urdf.string());
  const fs::path json = tmp.path() / "robot.json";
  write_file(json, io::write_character_json(*from_urdf.model));
  const LoadResult from_json = io::load_model_file(json.string());
  EXPECT_EQ(from_json.model->link_name, from_urdf.model->link_name);
  EXPECT_EQ(from_json.model->joint_type, from_urdf.model->joint_type);
  const std::string missing = (tmp.path() / "missing.urdf").string();
  EXPECT_EQ(error_of([&] { io::load_model_file(missing); }), missing + ": file not found");
}

}  // namespace
