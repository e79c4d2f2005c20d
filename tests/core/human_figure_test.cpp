// Tests for core/human_figure.hpp (the 48- and 34-DOF human figures) and for the bundled
// characters in characters/: the committed JSON files equal the generator's output, and the
// authored URDF arms load with the expected DOF and consistent kinematics.
//
// The de Leva (1996) numbers below are typed in again from the paper (Table 4, male), not read
// from the generator, so a slip in either copy shows up as a failure.
#include "core/human_figure.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/configuration.hpp"
#include "core/jacobian.hpp"
#include "core/kinematics.hpp"
#include "core/swing_twist.hpp"
#include "io/bundled_characters.hpp"
#include "io/character_json.hpp"
#include "io/urdf.hpp"
#include "tests/fixtures/fixtures.hpp"
#include "tests/fixtures/kinematics_checks.hpp"

namespace {

using namespace core;
constexpr double kPi = std::numbers::pi;
double deg(double d) { return d * kPi / 180.0; }

const std::vector<std::string> kLinks = {
    "pelvis",  "abdomen", "chest",   "neck",   "head",   "l_clav", "r_clav",
    "l_uarm",  "r_uarm",  "l_farm",  "r_farm", "l_hand", "r_hand", "l_thigh",
    "r_thigh", "l_shank", "r_shank", "l_foot", "r_foot", "l_toes", "r_toes"};

std::string mirror_name(const std::string& s) {
  if (s.rfind("l_", 0) == 0) return "r_" + s.substr(2);
  if (s.rfind("r_", 0) == 0) return "l_" + s.substr(2);
  return s;
}

const Matrix3 kMirror = Vector3(-1, 1, 1).asDiagonal();

int link(const Model& m, const std::string& name) {
  const int i = m.link_index(name);
  EXPECT_GE(i, 1) << "missing link " << name;
  return i;
}

// lowest and highest y over all collision shapes at configuration q
std::pair<double, double> vertical_extent(const Model& m, const Eigen::VectorXd& q) {
  Data d(m);
  forward_kinematics(m, d, q);
  double lo = kInfinity, hi = -kInfinity;
  for (int i = 1; i < m.njoints; ++i) {
    for (const Geometry& g : m.collision[i]) {
      const Transform X = d.X_W[i] * g.X_LinkShape;
      std::vector<Vector3> pts;
      double r = 0;
      switch (g.shape) {
        case Geometry::Shape::kSphere:
          pts = {X.p};
          r = g.radius;
          break;
        case Geometry::Shape::kCapsule:
          pts = {X * Vector3(0, 0, -0.5 * g.length), X * Vector3(0, 0, 0.5 * g.length)};
          r = g.radius;
          break;
        case Geometry::Shape::kBox:
          for (int c = 0; c < 8; ++c) {
            pts.push_back(X * Vector3((c & 1 ? 0.5 : -0.5) * g.size.x(),
                                      (c & 2 ? 0.5 : -0.5) * g.size.y(),
                                      (c & 4 ? 0.5 : -0.5) * g.size.z()));
          }
          break;
        default:
          ADD_FAILURE() << "unexpected shape on " << m.link_name[i];
      }
      for (const Vector3& p : pts) {
        lo = std::min(lo, p.y() - r);
        hi = std::max(hi, p.y() + r);
      }
    }
  }
  return {lo, hi};
}

// ---------------------------------------------------------------------------------------------
// structure
// ---------------------------------------------------------------------------------------------

TEST(HumanFigure, DegreesOfFreedomAndJointTypes) {
  const auto m48 = build_human_figure({.dof = 48});
  const auto m34 = build_human_figure({.dof = 34});
  EXPECT_EQ(m48->nv, 48);
  EXPECT_EQ(m34->nv, 34);
  EXPECT_EQ(m48->name, "human48");
  EXPECT_EQ(m34->name, "human34");
  EXPECT_EQ(m48->nlinks(), 21);
  EXPECT_EQ(m34->nlinks(), 21);
  using JT = JointType;
  const std::map<std::string, std::pair<JT, JT>> types = {
      // {48, 34}
      {"pelvis", {JT::kFree, JT::kFree}},           {"abdomen", {JT::kSpherical, JT::kSpherical}},
      {"chest", {JT::kSpherical, JT::kFixed}},      {"neck", {JT::kSpherical, JT::kSpherical}},
      {"head", {JT::kRevolute, JT::kFixed}},        {"l_clav", {JT::kRevolute, JT::kFixed}},
      {"l_uarm", {JT::kSpherical, JT::kSpherical}}, {"l_farm", {JT::kRevolute, JT::kRevolute}},
      {"l_hand", {JT::kSpherical, JT::kFixed}},     {"l_thigh", {JT::kSpherical, JT::kSpherical}},
      {"l_shank", {JT::kRevolute, JT::kRevolute}},  {"l_foot", {JT::kSpherical, JT::kSpherical}},
      {"l_toes", {JT::kRevolute, JT::kFixed}}};
  for (const auto& [name, t] : types) {
    for (const std::string& n : {name, mirror_name(name)}) {
      EXPECT_EQ(m48->joint_type[link(*m48, n)], t.first) << n;
      EXPECT_EQ(m34->joint_type[link(*m34, n)], t.second) << n;
    }
  }
  // the root is the pelvis
  EXPECT_EQ(m48->parent[link(*m48, "pelvis")], 0);
}

TEST(HumanFigure, RequiredLinksExistWithDisplayNames) {
  for (int dof : {34, 48}) {
    const auto m = build_human_figure({.dof = dof});
    for (const std::string& n : kLinks) {
      const int i = m->link_index(n);
      ASSERT_GE(i, 1) << n;
      EXPECT_FALSE(m->display_name[i].empty()) << n;
    }
    EXPECT_EQ(m->display_name[m->link_index("l_hand")], "Left hand");
    EXPECT_EQ(m->display_name[m->link_index("r_hand")], "Right hand");
    EXPECT_EQ(m->display_name[m->link_index("pelvis")], "Pelvis");
    // IK weights are set (spine stiffer than limbs), gains left to the solver
    EXPECT_GT(m->ik_weight[m->link_index("abdomen")], m->ik_weight[m->link_index("l_uarm")]);
    for (int i = 1; i < m->njoints; ++i) EXPECT_FALSE(m->ik_gain[i].has_value());
  }
}

TEST(HumanFigure, RejectsOptionsOutsideTheSupportedRange) {
  EXPECT_THROW(build_human_figure({.height = 0.4}), std::invalid_argument);
  EXPECT_THROW(build_human_figure({.height = 2.6}), std::invalid_argument);
  EXPECT_THROW(build_human_figure({.height = std::nan("")}), std::invalid_argument);
  EXPECT_THROW(build_human_figure({.mass = 9}), std::invalid_argument);
  EXPECT_THROW(build_human_figure({.mass = 301}), std::invalid_argument);
  EXPECT_THROW(build_human_figure({.dof = 40}), std::invalid_argument);
  EXPECT_NO_THROW(build_human_figure({.height = 0.5, .mass = 10, .dof = 34}));
  EXPECT_NO_THROW(build_human_figure({.height = 2.5, .mass = 300, .dof = 48}));
}

// ---------------------------------------------------------------------------------------------
// size and mass
// ---------------------------------------------------------------------------------------------

TEST(HumanFigure, TotalMassAndStandingHeightFollowTheOptions) {
  for (int dof : {34, 48}) {
    for (double h : {0.5, 1.2, 1.6, 1.75, 1.95, 2.5}) {
      for (double mass : {10.0, 45.0, 75.0, 120.0, 300.0}) {
        const auto m = build_human_figure({.height = h, .mass = mass, .dof = dof});
        EXPECT_NEAR(m->total_mass(), mass, 1e-9 * mass);
        const auto [lo, hi] = vertical_extent(*m, neutral_configuration(*m));
        // soles on the ground, top of the head at the stature
        EXPECT_NEAR(lo, 0.0, 1e-9) << h << " m, " << mass << " kg";
        EXPECT_NEAR(hi - lo, h, 0.01) << h << " m, " << mass << " kg";
      }
    }
  }
}

TEST(HumanFigure, SegmentMassesAreDeLevaFractions) {
  // de Leva (1996) Table 4, male: mass fractions
  const std::map<std::string, double> fraction = {{"head+neck", 0.0694},    {"upper trunk", 0.1596},
                                                  {"middle trunk", 0.1633}, {"lower trunk", 0.1117},
                                                  {"upper arm", 0.0271},    {"forearm", 0.0162},
                                                  {"hand", 0.0061},         {"thigh", 0.1416},
                                                  {"shank", 0.0433},        {"foot", 0.0137}};
  for (int dof : {34, 48}) {
    for (double mass : {50.0, 75.0, 110.0}) {
      const auto m = build_human_figure({.height = 1.8, .mass = mass, .dof = dof});
      auto mass_of = [&](const std::vector<std::string>& names) {
        double s = 0;
        for (const auto& n : names) s += m->inertia[link(*m, n)].mass;
        return s;
      };
      const double tol = 1e-12 * mass;
      EXPECT_NEAR(mass_of({"head", "neck"}), fraction.at("head+neck") * mass, tol);
      EXPECT_NEAR(mass_of({"chest", "l_clav", "r_clav"}), fraction.at("upper trunk") * mass, tol);
      EXPECT_NEAR(mass_of({"abdomen"}), fraction.at("middle trunk") * mass, tol);
      EXPECT_NEAR(mass_of({"pelvis"}), fraction.at("lower trunk") * mass, tol);
      for (const char* side : {"l_", "r_"}) {
        const std::string s = side;
        EXPECT_NEAR(mass_of({s + "uarm"}), fraction.at("upper arm") * mass, tol);
        EXPECT_NEAR(mass_of({s + "farm"}), fraction.at("forearm") * mass, tol);
        EXPECT_NEAR(mass_of({s + "hand"}), fraction.at("hand") * mass, tol);
        EXPECT_NEAR(mass_of({s + "thigh"}), fraction.at("thigh") * mass, tol);
        EXPECT_NEAR(mass_of({s + "shank"}), fraction.at("shank") * mass, tol);
        EXPECT_NEAR(mass_of({s + "foot", s + "toes"}), fraction.at("foot") * mass, tol);
      }
      // every link carries mass
      for (int i = 1; i < m->njoints; ++i) EXPECT_GT(m->inertia[i].mass, 0) << m->link_name[i];
    }
  }
}

struct Limb {
  const char* link;
  const char* next;  // the link whose joint ends the segment
  double length;     // m at 1.741 m
  double com;        // from the proximal joint, fraction of length
  double r_sag, r_trans, r_long;
};

TEST(HumanFigure, LimbLengthsCentresOfMassAndRadiiOfGyrationAreDeLeva) {
  // de Leva (1996) Table 4, male: length (mm), CM (%), radii sagittal/transverse/longitudinal (%)
  const std::vector<Limb> limbs = {
      {"l_uarm", "l_farm", 0.2817, 0.5772, 0.285, 0.269, 0.158},
      {"l_farm", "l_hand", 0.2689, 0.4574, 0.276, 0.265, 0.121},
      {"l_thigh", "l_shank", 0.4222, 0.4095, 0.329, 0.329, 0.149},
      {"l_shank", "l_foot", 0.4340, 0.4459, 0.255, 0.249, 0.103},
      // trunk pieces measured upward from the lower joint: CM fraction from the upper landmark
      {"abdomen", "chest", 0.2155, 1 - 0.4502, 0.482, 0.383, 0.468},
      {"pelvis", "abdomen", 0.1457, 1 - 0.6115, 0.615, 0.551, 0.587}};
  for (double h : {1.5, 1.741, 1.9}) {
    const auto m = build_human_figure({.height = h, .mass = 80});
    const double s = h / 1.741;
    for (const Limb& l : limbs) {
      const int i = link(*m, l.link), j = link(*m, l.next);
      const double L = m->X_PJ[j].p.norm();
      EXPECT_NEAR(L, l.length * s, 1e-12) << l.link;
      const Vector3 c = m->inertia[i].com();
      EXPECT_NEAR(c.dot(m->X_PJ[j].p.normalized()), l.com * L, 1e-12) << l.link;
      EXPECT_NEAR(c.norm(), l.com * L, 1e-12) << l.link;
      // x medio-lateral (transverse), y longitudinal, z antero-posterior (sagittal)
      const Matrix3 I = m->inertia[i].inertia_about_com();
      const double mass = m->inertia[i].mass;
      EXPECT_NEAR(std::sqrt(I(0, 0) / mass) / L, l.r_trans, 1e-9) << l.link;
      EXPECT_NEAR(std::sqrt(I(1, 1) / mass) / L, l.r_long, 1e-9) << l.link;
      EXPECT_NEAR(std::sqrt(I(2, 2) / mass) / L, l.r_sag, 1e-9) << l.link;
    }
  }
}

// composite of several links at the neutral pose, in world coordinates
SpatialInertia composite(const Model& m, const std::vector<std::string>& names) {
  Data d(m);
  forward_kinematics(m, d, neutral_configuration(m));
  SpatialInertia sum;
  for (const auto& n : names) sum += m.inertia[link(m, n)].transformed(d.X_W[link(m, n)]);
  return sum;
}

TEST(HumanFigure, SplitSegmentsRecombineIntoDeLevasSegments) {
  const double h = 1.8, mass = 70, s = h / 1.741;
  for (int dof : {34, 48}) {
    const auto m = build_human_figure({.height = h, .mass = mass, .dof = dof});
    Data d(*m);
    forward_kinematics(*m, d, neutral_configuration(*m));
    auto y_of = [&](const char* n) { return d.X_W[link(*m, n)].p.y(); };
    auto expect_radii = [&](const SpatialInertia& c, double L, const Vector3& r, const char* what) {
      const Matrix3 I = c.inertia_about_com();
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(std::sqrt(I(k, k) / c.mass) / L, r[k], 1e-9) << what << " axis " << k;
      }
      EXPECT_NEAR(I(0, 1), 0.0, 1e-12) << what;
      EXPECT_NEAR(I(1, 2), 0.0, 1e-12) << what;
      EXPECT_NEAR(I(0, 2), 0.0, 1e-12) << what;
    };
    // upper trunk (chest + shoulder girdles): CERV → XYPH 242.1 mm, CM 50.66 % below CERV,
    // radii transverse 32.0, longitudinal 46.5, sagittal 50.5 %
    const SpatialInertia upt = composite(*m, {"chest", "l_clav", "r_clav"});
    const double L_upt = 0.2421 * s;
    EXPECT_NEAR(y_of("neck") - y_of("chest"), L_upt, 1e-12);
    EXPECT_NEAR(upt.com().y(), y_of("neck") - 0.5066 * L_upt, 1e-12);
    EXPECT_NEAR(upt.com().x(), 0.0, 1e-12);
    EXPECT_NEAR(upt.com().z(), 0.0, 1e-12);
    expect_radii(upt, L_upt, {0.320, 0.465, 0.505}, "upper trunk");
    // head + neck: CM 50.02 % of VERT → CERV (242.9 mm) below the vertex
    const SpatialInertia hn = composite(*m, {"head", "neck"});
    EXPECT_NEAR(hn.com().y(), h - 0.5002 * 0.2429 * s, 1e-12);
    expect_radii(hn, 0.2429 * s, {0.315, 0.261, 0.303}, "head + neck");
    // foot + toes: CM 44.15 % of HEEL → TTIP (258.1 mm) from the heel; the long axis is z
    for (const char* side : {"l_", "r_"}) {
      const std::string sd = side;
      const SpatialInertia f = composite(*m, {sd + "foot", sd + "toes"});
      const double L = 0.2581 * s;
      const auto [lo, hi] = [&] {
        double zmin = kInfinity, zmax = -kInfinity;
        for (const std::string& n : {sd + "foot", sd + "toes"}) {
          const int i = link(*m, n);
          for (const Geometry& g : m->collision[i]) {
            const Vector3 c = d.X_W[i] * g.X_LinkShape.p;
            zmin = std::min(zmin, c.z() - 0.5 * g.size.z());
            zmax = std::max(zmax, c.z() + 0.5 * g.size.z());
          }
        }
        return std::pair{zmin, zmax};
      }();
      EXPECT_NEAR(hi - lo, L, 1e-12) << "heel to toe tip";
      EXPECT_NEAR(f.com().z(), lo + 0.4415 * L, 1e-12);
      expect_radii(f, L, {0.245, 0.257, 0.124}, "foot");
    }
  }
}

TEST(HumanFigure, EveryInertiaIsPhysical) {
  for (int dof : {34, 48}) {
    const auto m = build_human_figure({.height = 1.75, .mass = 75, .dof = dof});
    for (int i = 1; i < m->njoints; ++i) {
      const Eigen::Vector3d e =
          Eigen::SelfAdjointEigenSolver<Matrix3>(m->inertia[i].inertia_about_com()).eigenvalues();
      EXPECT_GT(e(0), 0) << m->link_name[i];
      EXPECT_GE(e(0) + e(1), e(2) * (1 + 1e-12)) << m->link_name[i] << ": triangle inequality";
    }
  }
}

// ---------------------------------------------------------------------------------------------
// symmetry
// ---------------------------------------------------------------------------------------------

// q of the mirror-image pose: l_ ↔ r_ swapped, rotations reflected in the x = 0 plane
Eigen::VectorXd mirrored_configuration(const Model& m, const Eigen::VectorXd& q) {
  Eigen::VectorXd out = q;
  for (int i = 1; i < m.njoints; ++i) {
    const int j = m.link_index(mirror_name(m.link_name[i]));
    const int iq = m.idx_q[i], jq = m.idx_q[j];
    switch (m.joint_type[i]) {
      case JointType::kFixed:
        break;
      case JointType::kRevolute:
      case JointType::kPrismatic:
        out[jq] = q[iq];
        break;
      case JointType::kSpherical: {
        const Quaternion r = quaternion_at(q, iq);
        set_quaternion_at(out, jq, Quaternion(r.w(), r.x(), -r.y(), -r.z()));
        break;
      }
      case JointType::kFree: {
        out.segment<3>(jq) = kMirror * q.segment<3>(iq);
        const Quaternion r = quaternion_at(q, iq + 3);
        set_quaternion_at(out, jq + 3, Quaternion(r.w(), r.x(), -r.y(), -r.z()));
        break;
      }
    }
  }
  return out;
}

TEST(HumanFigure, LeftAndRightAreMirrorImagesAtNeutral) {
  for (int dof : {34, 48}) {
    const auto m = build_human_figure({.height = 1.75, .mass = 75, .dof = dof});
    Data d(*m);
    forward_kinematics(*m, d, neutral_configuration(*m));
    for (int i = 1; i < m->njoints; ++i) {
      const int j = link(*m, mirror_name(m->link_name[i]));
      const std::string& n = m->link_name[i];
      // link frames aligned with the world at neutral
      EXPECT_TRUE(d.X_W[i].R.isIdentity(1e-15)) << n;
      EXPECT_NEAR((d.X_W[j].p - kMirror * d.X_W[i].p).norm(), 0.0, 1e-15) << n;
      if (i == j)
        EXPECT_EQ(d.X_W[i].p.x(), 0.0) << n << " lies on the midline";
      else
        EXPECT_GT(n[0] == 'l' ? d.X_W[i].p.x() : -d.X_W[i].p.x(), 0.0) << n << ": left is +x";
      // mass properties mirrored
      EXPECT_EQ(m->inertia[j].mass, m->inertia[i].mass) << n;
      EXPECT_NEAR((m->inertia[j].h - kMirror * m->inertia[i].h).norm(), 0.0, 1e-15) << n;
      EXPECT_NEAR((m->inertia[j].I_O - kMirror * m->inertia[i].I_O * kMirror).norm(), 0.0, 1e-15)
          << n;
      EXPECT_EQ(m->limits[j], m->limits[i]) << n;
      EXPECT_EQ(m->ik_weight[j], m->ik_weight[i]) << n;
    }
    // facing +z: the toes are in front of the ankles, the head above the pelvis
    EXPECT_GT(d.X_W[link(*m, "l_toes")].p.z(), d.X_W[link(*m, "l_foot")].p.z());
    EXPECT_GT(d.X_W[link(*m, "head")].p.y(), d.X_W[link(*m, "pelvis")].p.y());
  }
}

TEST(HumanFigure, MirroredConfigurationsGiveMirroredPosesAndRangeVerdicts) {
  for (int dof : {34, 48}) {
    const auto m = build_human_figure({.height = 1.75, .mass = 75, .dof = dof});
    Data d(*m), dm(*m);
    for (std::uint64_t seed = 0; seed < 20; ++seed) {
      const Eigen::VectorXd q = random_configuration(*m, seed);
      const Eigen::VectorXd qm = mirrored_configuration(*m, q);
      forward_kinematics(*m, d, q);
      forward_kinematics(*m, dm, qm);
      for (int i = 1; i < m->njoints; ++i) {
        const int j = m->link_index(mirror_name(m->link_name[i]));
        EXPECT_TRUE(dm.X_W[j].p.isApprox(kMirror * d.X_W[i].p, 1e-12)) << m->link_name[i];
        EXPECT_TRUE(dm.X_W[j].R.isApprox(kMirror * d.X_W[i].R * kMirror, 1e-12)) << m->link_name[i];
        if (m->joint_type[i] != JointType::kSpherical) continue;
        const RangeStatus a = check_range(m->spherical_range[i],
                                          joint_swing_twist(*m, i, quaternion_at(q, m->idx_q[i])));
        const RangeStatus b = check_range(m->spherical_range[j],
                                          joint_swing_twist(*m, j, quaternion_at(qm, m->idx_q[j])));
        EXPECT_EQ(a.inside, b.inside) << m->link_name[i] << " seed " << seed;
        EXPECT_NEAR(a.violation, b.violation, 1e-9) << m->link_name[i] << " seed " << seed;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// ranges
// ---------------------------------------------------------------------------------------------

TEST(HumanFigure, NeutralAndRestOrientationsLieInsideEveryRange) {
  for (int dof : {34, 48}) {
    const auto m = build_human_figure({.dof = dof});
    int spherical = 0;
    for (int i = 1; i < m->njoints; ++i) {
      const std::string& n = m->link_name[i];
      if (m->joint_type[i] == JointType::kRevolute) {
        EXPECT_LT(m->limits[i].lower, 0.0) << n;
        EXPECT_GT(m->limits[i].upper, 0.0) << n;
      }
      if (m->joint_type[i] != JointType::kSpherical) continue;
      ++spherical;
      const SphericalRange& r = m->spherical_range[i];
      ASSERT_FALSE(r.empty()) << n << " has no range";
      const RangeStatus neutral = check_range(r, joint_swing_twist(*m, i, Quaternion::Identity()));
      EXPECT_TRUE(neutral.inside) << n;
      const RangeStatus rest = check_range(r, joint_swing_twist(*m, i, m->standard_orientation[i]));
      EXPECT_TRUE(rest.inside) << n;
      // the neutral pose is not on the boundary: small rotations about any axis stay inside
      for (int k = 0; k < 3; ++k) {
        const Vector3 axis = Vector3::Unit(k);
        for (double sgn : {-1.0, 1.0}) {
          const Quaternion q(Eigen::AngleAxisd(sgn * deg(3), axis));
          EXPECT_TRUE(check_range(r, joint_swing_twist(*m, i, q)).inside) << n;
        }
      }
    }
    EXPECT_EQ(spherical, dof == 48 ? 11 : 8);
  }
}

TEST(HumanFigure, SingularDirectionLiesWellOutsideEveryRange) {
  for (int dof : {34, 48}) {
    const auto m = build_human_figure({.dof = dof});
    for (int i = 1; i < m->njoints; ++i) {
      if (m->joint_type[i] != JointType::kSpherical) continue;
      const SphericalRange& r = m->spherical_range[i];
      // swing of π toward every direction (the nominal direction reversed) is outside
      for (int k = 0; k < 360; ++k) {
        const double psi = deg(k);
        const SwingTwist st{-std::sin(psi), std::cos(psi), 0.0, true};
        EXPECT_FALSE(check_range(r, st).inside) << m->link_name[i] << " psi " << k;
      }
      // and at least 30° away: no vertex swings more than 150°
      for (const Eigen::Vector2d& a : r.swing) {
        EXPECT_LE(2 * std::asin(std::min(1.0, a.norm())), deg(150) + 1e-12) << m->link_name[i];
      }
    }
  }
}

// a rotation of the joint by angle about a joint-frame axis is inside its range
bool inside(const Model& m, const std::string& n, const Vector3& axis, double angle) {
  const int i = m.link_index(n);
  const Quaternion q(Eigen::AngleAxisd(angle, axis.normalized()));
  return check_range(m.spherical_range[i], joint_swing_twist(m, i, q)).inside;
}

TEST(HumanFigure, ShouldersAndHipsFollowClinicalDirectionalLimits) {
  for (int dof : {34, 48}) {
    const auto m = build_human_figure({.dof = dof});
    for (const char* side : {"l_", "r_"}) {
      const std::string s = side;
      const double lat = s == "l_" ? 1.0 : -1.0;  // +x is lateral on the left
      // direction-dependent triangle patches with at least 8 rim directions
      for (const char* n : {"uarm", "thigh"}) {
        EXPECT_GE(m->spherical_range[link(*m, s + n)].triangles.size(), 8u);
      }
      // flexion: the limb swings forward (−y → +z), a rotation about −x
      const Vector3 flex = -Vector3::UnitX();
      // abduction: the limb swings laterally, about +z on the left, −z on the right
      const Vector3 abd = lat * Vector3::UnitZ();
      // internal rotation about the long axis: about −y on the left, +y on the right
      const Vector3 internal = -lat * Vector3::UnitY();
      // hip (AAOS): flexion 120, extension 30, abduction 45, adduction 30, rotation 45/45
      const std::string hip = s + "thigh";
      EXPECT_TRUE(inside(*m, hip, flex, deg(115)));
      EXPECT_FALSE(inside(*m, hip, flex, deg(125)));
      EXPECT_TRUE(inside(*m, hip, -flex, deg(25)));
      EXPECT_FALSE(inside(*m, hip, -flex, deg(35)));
      EXPECT_TRUE(inside(*m, hip, abd, deg(40)));
      EXPECT_FALSE(inside(*m, hip, abd, deg(50)));
      EXPECT_TRUE(inside(*m, hip, -abd, deg(25)));
      EXPECT_FALSE(inside(*m, hip, -abd, deg(35)));
      EXPECT_TRUE(inside(*m, hip, internal, deg(40)));
      EXPECT_FALSE(inside(*m, hip, internal, deg(50)));
      EXPECT_TRUE(inside(*m, hip, -internal, deg(40)));
      EXPECT_FALSE(inside(*m, hip, -internal, deg(50)));
      // shoulder: flexion and abduction 150 (the girdle adds the rest), extension 60,
      // adduction 30, internal rotation 70, external 80 at the side
      const std::string sh = s + "uarm";
      EXPECT_TRUE(inside(*m, sh, flex, deg(145)));
      EXPECT_FALSE(inside(*m, sh, flex, deg(155)));
      EXPECT_TRUE(inside(*m, sh, abd, deg(145)));
      EXPECT_FALSE(inside(*m, sh, abd, deg(155)));
      EXPECT_TRUE(inside(*m, sh, -flex, deg(55)));
      EXPECT_FALSE(inside(*m, sh, -flex, deg(65)));
      EXPECT_TRUE(inside(*m, sh, -abd, deg(25)));
      EXPECT_FALSE(inside(*m, sh, -abd, deg(35)));
      EXPECT_TRUE(inside(*m, sh, internal, deg(65)));
      EXPECT_FALSE(inside(*m, sh, internal, deg(75)));
      EXPECT_TRUE(inside(*m, sh, -internal, deg(75)));
      EXPECT_FALSE(inside(*m, sh, -internal, deg(85)));
      // across the body at shoulder height (horizontal adduction) is reachable
      const Vector3 cross_body = (flex + (-abd)).normalized();
      EXPECT_TRUE(inside(*m, sh, cross_body, deg(90)));
    }
  }
}

TEST(HumanFigure, OneDofJointsMoveTheRightWay) {
  const auto m = build_human_figure({.dof = 48});
  Data d(*m);
  Eigen::VectorXd q = neutral_configuration(*m);
  forward_kinematics(*m, d, q);
  const std::vector<Transform> X0 = d.X_W;
  auto moved = [&](const char* joint_link, const char* probe, double angle) {
    Eigen::VectorXd qq = q;
    qq[m->idx_q[link(*m, joint_link)]] = angle;
    forward_kinematics(*m, d, qq);
    return Vector3(d.X_W[link(*m, probe)].p - X0[link(*m, probe)].p);
  };
  for (const char* side : {"l_", "r_"}) {
    const std::string s = side;
    // knee flexion moves the ankle backward, elbow flexion moves the wrist forward
    EXPECT_LT(moved((s + "shank").c_str(), (s + "foot").c_str(), deg(45)).z(), -0.1);
    EXPECT_GT(moved((s + "farm").c_str(), (s + "hand").c_str(), deg(45)).z(), 0.05);
    // clavicle elevation lifts the shoulder
    EXPECT_GT(moved((s + "clav").c_str(), (s + "uarm").c_str(), deg(20)).y(), 0.01);
    // toe flexion lowers the toe tip
    Eigen::VectorXd qq = q;
    const int toes = link(*m, s + "toes");
    qq[m->idx_q[toes]] = deg(30);
    forward_kinematics(*m, d, qq);
    const Vector3 tip(0, 0, 0.05);
    EXPECT_LT((d.X_W[toes] * tip).y(), (X0[toes] * tip).y() - 0.01);
  }
  // head nod (flexion) brings the top of the head forward
  {
    Eigen::VectorXd qq = q;
    qq[m->idx_q[link(*m, "head")]] = deg(10);
    forward_kinematics(*m, d, qq);
    const Vector3 top = d.X_W[link(*m, "head")] * Vector3(0, 0.1, 0);
    EXPECT_GT(top.z(), 0.01);
  }
}

// ---------------------------------------------------------------------------------------------
// kinematics on random configurations
// ---------------------------------------------------------------------------------------------

TEST(HumanFigure, JacobiansAndJdotVMatchFiniteDifferences) {
  for (int dof : {34, 48}) {
    const auto m = build_human_figure({.height = 1.75, .mass = 75, .dof = dof});
    for (std::uint64_t seed = 0; seed < 4; ++seed) {
      const Eigen::VectorXd q = random_configuration(*m, seed);
      fixtures::expect_jacobians_match_finite_differences(*m, q, 1e-6);
      const Eigen::VectorXd v = difference(*m, q, random_configuration(*m, seed + 50));
      fixtures::expect_jdot_v_matches_finite_differences(*m, q, v, 1e-5);
    }
  }
}

// The benchmark twin in the shared bench folder (revolute triplets, Z up, built independently
// from de Leva for 1.75 m and 75 kg) agrees on every de Leva-derived quantity.
TEST(HumanFigure, AgreesWithTheBenchmarkTwinOnDeLevaQuantities) {
  PINDRAG_REQUIRE_BENCH_DIR();
  const io::LoadResult twin = io::load_urdf_file(fixtures::bench_models_dir() + "/human48.urdf",
                                                 {.root = io::RootJoint::kFree});
  const Model& b = *twin.model;
  const auto m = build_human_figure({.height = 1.75, .mass = 75, .dof = 48});
  Data db(b), dm(*m);
  forward_kinematics(b, db, neutral_configuration(b));
  forward_kinematics(*m, dm, neutral_configuration(*m));
  auto mass = [](const Model& mod, const std::vector<std::string>& names) {
    double s = 0;
    for (const auto& n : names) s += mod.inertia[link(mod, n)].mass;
    return s;
  };
  for (const std::vector<std::string>& seg :
       std::vector<std::vector<std::string>>{{"pelvis"},
                                             {"abdomen"},
                                             {"chest", "l_clav", "r_clav"},
                                             {"neck", "head"},
                                             {"l_uarm"},
                                             {"r_farm"},
                                             {"l_hand"},
                                             {"r_thigh"},
                                             {"l_shank"},
                                             {"r_foot", "r_toes"}}) {
    EXPECT_NEAR(mass(*m, seg), mass(b, seg), 1e-9) << seg.front();
  }
  // joint-to-joint vectors of de Leva segments, world axes
  auto offset = [](const Model& mod, const Data& d, const char* from, const char* to) {
    return Vector3(d.X_W[link(mod, to)].p - d.X_W[link(mod, from)].p);
  };
  for (const auto& [from, to] :
       std::vector<std::pair<const char*, const char*>>{{"pelvis", "abdomen"},
                                                        {"abdomen", "chest"},
                                                        {"chest", "neck"},
                                                        {"l_uarm", "l_farm"},
                                                        {"r_farm", "r_hand"},
                                                        {"l_thigh", "l_shank"},
                                                        {"r_shank", "r_foot"}}) {
    EXPECT_TRUE(offset(*m, dm, from, to).isApprox(offset(b, db, from, to), 1e-9))
        << from << " → " << to << ": " << offset(*m, dm, from, to).transpose() << " vs "
        << offset(b, db, from, to).transpose();
  }
  // centres of mass and inertias about them, world axes, for segments both model the same way
  for (const char* n : {"pelvis", "abdomen", "l_uarm", "r_farm", "l_hand", "r_thigh", "l_shank"}) {
    const SpatialInertia im = m->inertia[link(*m, n)].transformed(dm.X_W[link(*m, n)]);
    const SpatialInertia ib = b.inertia[link(b, n)].transformed(db.X_W[link(b, n)]);
    const Vector3 base_m = dm.X_W[link(*m, n)].p, base_b = db.X_W[link(b, n)].p;
    EXPECT_TRUE((im.com() - base_m).isApprox(ib.com() - base_b, 1e-9)) << n;
    EXPECT_TRUE(im.inertia_about_com().isApprox(ib.inertia_about_com(), 1e-9)) << n;
  }
}

// ---------------------------------------------------------------------------------------------
// bundled characters
// ---------------------------------------------------------------------------------------------

// the source tree's characters/ folder (recorded at build time, or $PINDRAG_CHARACTERS_DIR)
std::string character_path(const std::string& file) { return io::characters_dir() + "/" + file; }

TEST(BundledCharacters, CommittedHumanFiguresEqualTheGenerator) {
  for (int dof : {48, 34}) {
    const std::string path = character_path("human" + std::to_string(dof) + ".json");
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    const io::LoadResult loaded = io::load_character_json_file(path);
    ASSERT_TRUE(loaded.model);
    EXPECT_TRUE(loaded.warnings.empty());
    const auto generated = build_human_figure({.height = 1.75, .mass = 75, .dof = dof});
    // source_dir is where the file was found, not part of the figure
    Model a = *loaded.model;
    a.source_dir = generated->source_dir;
    EXPECT_TRUE(a == *generated) << path << " differs from build_human_figure(1.75 m, 75 kg, "
                                 << dof << " DOF): regenerate it with `pindrag character`";
    EXPECT_EQ(io::write_character_json(*loaded.model), io::write_character_json(*generated));
  }
}

TEST(BundledCharacters, Arm7LoadsAsASevenDofFixedBaseArm) {
  const io::LoadResult r = io::load_urdf_file(character_path("arm7.urdf"));
  ASSERT_TRUE(r.model);
  const Model& m = *r.model;
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  EXPECT_EQ(m.nv, 7);
  EXPECT_EQ(m.nq, 7);
  int revolute = 0;
  for (int i = 1; i < m.njoints; ++i) {
    if (m.joint_type[i] != JointType::kRevolute) continue;
    ++revolute;
    EXPECT_TRUE(std::isfinite(m.limits[i].lower) && std::isfinite(m.limits[i].upper));
    EXPECT_GT(m.inertia[i].mass, 0) << m.link_name[i];
  }
  EXPECT_EQ(revolute, 7);
  // upright at zero: the flange is straight above the base (URDF z up → our y up)
  Data d(m);
  forward_kinematics(m, d, neutral_configuration(m));
  const Vector3 p = d.X_W[link(m, "flange")].p;
  EXPECT_NEAR(p.x(), 0.0, 1e-12);
  EXPECT_NEAR(p.z(), 0.0, 1e-12);
  EXPECT_NEAR(p.y(), 1.22, 1e-12);
  // consecutive joint axes alternate (roll, pitch, roll, ...): neighbours are perpendicular
  std::vector<Vector3> axes_W;
  for (int i = 1; i < m.njoints; ++i) {
    if (m.joint_type[i] == JointType::kRevolute) axes_W.push_back(d.X_W[i].R * m.axis[i]);
  }
  for (size_t k = 0; k + 1 < axes_W.size(); ++k) {
    EXPECT_NEAR(axes_W[k].dot(axes_W[k + 1]), 0.0, 1e-12) << "joints " << k + 1 << ", " << k + 2;
  }
  for (std::uint64_t seed = 0; seed < 5; ++seed) {
    const Eigen::VectorXd q = random_configuration(m, seed);
    fixtures::expect_jacobians_match_finite_differences(m, q, 1e-6);
    fixtures::expect_jdot_v_matches_finite_differences(
        m, q, difference(m, q, random_configuration(m, seed + 9)), 1e-5);
  }
}

TEST(BundledCharacters, Manipulator5LoadsWithItsDhGeometryAndLoad) {
  const io::LoadResult r = io::load_urdf_file(character_path("manipulator5.urdf"));
  ASSERT_TRUE(r.model);
  const Model& m = *r.model;
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  EXPECT_EQ(m.nv, 5);
  // 3200 N on the last link: the load's mass at g = 9.81 m/s²
  EXPECT_NEAR(m.inertia[link(m, "load")].mass * 9.81, 3200.0, 0.5);
  Data d(m);
  forward_kinematics(m, d, neutral_configuration(m));
  // joint 1 vertical; joints 2–4 parallel and horizontal; joint 5 vertical at zero
  std::vector<Vector3> axes_W;
  for (int i = 1; i < m.njoints; ++i) {
    if (m.joint_type[i] == JointType::kRevolute) axes_W.push_back(d.X_W[i].R * m.axis[i]);
  }
  ASSERT_EQ(axes_W.size(), 5u);
  EXPECT_NEAR(std::abs(axes_W[0].y()), 1.0, 1e-12);
  for (int k = 1; k <= 3; ++k) {
    EXPECT_NEAR(axes_W[k].y(), 0.0, 1e-12) << "joint " << k + 1 << " is horizontal";
    EXPECT_NEAR(std::abs(axes_W[k].dot(axes_W[1])), 1.0, 1e-12) << "joint " << k + 1;
  }
  EXPECT_NEAR(std::abs(axes_W[4].y()), 1.0, 1e-12);
  // DH lengths (README): reach a1 + a2 + a3 + a4 = 4.0 m at zero, load 0.475 m below joint 5
  const Vector3 p_load = d.X_W[link(m, "load")].p;
  EXPECT_NEAR(std::hypot(p_load.x(), p_load.z()), 4.0, 1e-12);
  EXPECT_NEAR(p_load.y(), 0.9 - 0.475, 1e-12);
  // keeping θ2 + θ3 + θ4 = 0 keeps the load level (its vertical axis stays vertical)
  Eigen::VectorXd q = neutral_configuration(m);
  q << 0.7, 0.4, -0.9, 0.5, -0.3;
  forward_kinematics(m, d, q);
  EXPECT_NEAR(std::abs((d.X_W[link(m, "load")].R * m.axis[link(m, "link5")]).y()), 1.0, 1e-12);
  for (std::uint64_t seed = 0; seed < 5; ++seed) {
    const Eigen::VectorXd qr = random_configuration(m, seed);
    fixtures::expect_jacobians_match_finite_differences(m, qr, 1e-6);
    fixtures::expect_jdot_v_matches_finite_differences(
        m, qr, difference(m, qr, random_configuration(m, seed + 9)), 1e-5);
  }
}

}  // namespace
