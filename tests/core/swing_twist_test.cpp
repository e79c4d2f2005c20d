// Tests for core/swing_twist.hpp (Yamane §8.3.5, digest §2.5 and hard cases #6, #7).
#include "core/swing_twist.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/configuration.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using namespace core;
constexpr double kPi = std::numbers::pi;

TEST(SwingTwist, RecompositionReproducesTheRotation) {
  const auto m = fixtures::branching_tree();
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    const Eigen::VectorXd q = random_configuration(*m, seed);
    const Quaternion r = quaternion_at(q, m->idx_q[m->link_index("ball")]);
    const SwingTwist st = swing_twist(r);
    ASSERT_FALSE(st.singular);
    const Quaternion back = from_swing_twist(st.a_y, st.a_z, st.twist);
    EXPECT_TRUE(back.toRotationMatrix().isApprox(r.toRotationMatrix(), 1e-12)) << seed;
    // a_y² + a_z² = sin²(φ/2) = (1 − R(1,1)) / 2
    const double R11 = r.toRotationMatrix()(0, 0);
    EXPECT_NEAR(st.a_y * st.a_y + st.a_z * st.a_z, (1.0 - R11) / 2.0, 1e-12);
    // sign invariance: q and −q are the same rotation
    const SwingTwist neg = swing_twist(Quaternion(-r.w(), -r.x(), -r.y(), -r.z()));
    EXPECT_NEAR(neg.a_y, st.a_y, 1e-15);
    EXPECT_NEAR(neg.a_z, st.a_z, 1e-15);
    EXPECT_NEAR(std::cos(neg.twist), std::cos(st.twist), 1e-15);
  }
}

TEST(SwingTwist, MatchesTheBookFormulaFromTheMatrix) {
  // a_y = −R(3,1) / sqrt(2(1 + R(1,1))), a_z = R(2,1) / sqrt(2(1 + R(1,1)))   (Yamane 8.28–8.29)
  const Quaternion r = Quaternion(Eigen::AngleAxisd(1.1, Vector3(0.2, -0.5, 0.8).normalized()));
  const Matrix3 R = r.toRotationMatrix();
  const SwingTwist st = swing_twist(r);
  const double d = std::sqrt(2 * (1 + R(0, 0)));
  EXPECT_NEAR(st.a_y, -R(2, 0) / d, 1e-14);
  EXPECT_NEAR(st.a_z, R(1, 0) / d, 1e-14);
}

TEST(SwingTwist, PureTwistAndPureSwing) {
  const SwingTwist t = swing_twist(Quaternion(Eigen::AngleAxisd(0.7, Vector3::UnitX())));
  EXPECT_NEAR(t.twist, 0.7, 1e-15);
  EXPECT_NEAR(std::hypot(t.a_y, t.a_z), 0.0, 1e-15);
  // tilting x toward +y by 60° is a swing about +z
  const SwingTwist s = swing_twist(Quaternion(Eigen::AngleAxisd(kPi / 3, Vector3::UnitZ())));
  EXPECT_NEAR(s.a_z, std::sin(kPi / 6), 1e-15);
  EXPECT_NEAR(s.a_y, 0.0, 1e-15);
  const Eigen::Vector2d a = swing_toward(0.0, kPi / 3);
  EXPECT_NEAR(a.x(), s.a_y, 1e-15);
  EXPECT_NEAR(a.y(), s.a_z, 1e-15);
}

TEST(SwingTwist, SingularDirectionIsFlaggedNotNaN) {
  // hard case #6: R(1,1) = −1, the link points opposite its nominal direction
  const Quaternion r(Eigen::AngleAxisd(kPi, Vector3(0, 0.6, 0.8)));
  const SwingTwist st = swing_twist(r);
  EXPECT_TRUE(st.singular);
  EXPECT_TRUE(std::isfinite(st.a_y) && std::isfinite(st.a_z) && std::isfinite(st.twist));
  EXPECT_NEAR(std::hypot(st.a_y, st.a_z), 1.0, 1e-12);
  // just off the singular direction the decomposition is still exact
  const Quaternion near(Eigen::AngleAxisd(kPi - 1e-6, Vector3(0, 0.6, 0.8)));
  const SwingTwist sn = swing_twist(near);
  EXPECT_FALSE(sn.singular);
  EXPECT_TRUE(from_swing_twist(sn.a_y, sn.a_z, sn.twist)
                  .toRotationMatrix()
                  .isApprox(near.toRotationMatrix(), 1e-9));
}

TEST(SwingTwist, TriangleInsideOutsideAndTwistInterpolation) {
  SphericalRange r;
  r.swing = {{0, 0}, {0.5, 0}, {0, 0.5}};
  r.triangles = {{0, 1, 2}};
  r.twist_lower = {-0.2, -0.6, -0.2};
  r.twist_upper = {0.2, 0.6, 0.2};
  // inside the triangle, twist inside the interpolated limits
  RangeStatus s = check_range(r, {0.1, 0.1, 0.0});
  EXPECT_TRUE(s.inside);
  // at (0.25, 0): barycentric (0.5, 0.5, 0) → limits ±0.4
  s = check_range(r, {0.25, 0.0, 0.35});
  EXPECT_TRUE(s.inside);
  EXPECT_NEAR(s.twist_upper, 0.4, 1e-15);
  s = check_range(r, {0.25, 0.0, 0.45});
  EXPECT_FALSE(s.inside);
  EXPECT_NEAR(s.violation, 0.05, 1e-12);
  // swing outside every triangle
  s = check_range(r, {0.4, 0.4, 0.0});
  EXPECT_FALSE(s.inside);
  EXPECT_EQ(s.triangle, -1);
  EXPECT_GT(s.violation, 0.0);
  s = check_range(r, {-0.1, 0.0, 0.0});
  EXPECT_FALSE(s.inside);
  EXPECT_NEAR(s.violation, 0.2, 1e-12);  // 2 × distance 0.1 in the swing plane
  // an empty range accepts everything
  EXPECT_TRUE(check_range(SphericalRange{}, {0.9, 0.1, 3.0}).inside);
}

TEST(SwingTwist, TwistLimitsMayStraddleTheWrap) {
  // hard case #7: twist allowed in [150°, 210°], i.e. across ±180°
  const SphericalRange r = cone_range(0.5, 150 * kPi / 180, 210 * kPi / 180);
  EXPECT_TRUE(check_range(r, swing_twist(from_swing_twist(0, 0, kPi))).inside);
  EXPECT_TRUE(check_range(r, swing_twist(from_swing_twist(0, 0, -170 * kPi / 180))).inside);
  EXPECT_TRUE(check_range(r, swing_twist(from_swing_twist(0, 0, 170 * kPi / 180))).inside);
  const RangeStatus s = check_range(r, swing_twist(from_swing_twist(0, 0, 0.0)));
  EXPECT_FALSE(s.inside);
  EXPECT_NEAR(s.violation, 150 * kPi / 180, 1e-12);
  // −140° is 10° past the upper limit of 210° (= −150°)
  EXPECT_NEAR(check_range(r, swing_twist(from_swing_twist(0, 0, -140 * kPi / 180))).violation,
              10 * kPi / 180, 1e-12);
}

TEST(SwingTwist, ConeIsATriangleFan) {
  const SphericalRange r = cone_range(kPi / 4, -0.5, 0.5, 16);
  EXPECT_EQ(r.triangles.size(), 16u);
  EXPECT_EQ(r.swing.size(), 17u);
  for (double psi = 0; psi < 2 * kPi; psi += 0.1) {
    // a swing of 40° in any direction is inside (the inscribed polygon reaches cos(π/16) of 45°)
    const Eigen::Vector2d in = swing_toward(psi, 40 * kPi / 180);
    EXPECT_TRUE(check_range(r, {in.x(), in.y(), 0.3}).inside) << psi;
    const Eigen::Vector2d out = swing_toward(psi, 50 * kPi / 180);
    EXPECT_FALSE(check_range(r, {out.x(), out.y(), 0.0}).inside) << psi;
  }
}

TEST(SwingTwist, JointRangeFrameMapsTheNominalDirection) {
  // a joint whose limb hangs along −y: the range frame maps x to −y
  ModelBuilder b;
  LinkSpec root = fixtures::box_link("root", "", 1, Vector3::Ones());
  b.add_link(root);
  LinkSpec l = fixtures::box_link("leg", "root", 1, Vector3::Ones());
  l.joint.type = JointType::kSpherical;
  l.joint.range = cone_range(kPi / 6, -0.1, 0.1);
  l.joint.range.frame = Quaternion::FromTwoVectors(Vector3::UnitX(), -Vector3::UnitY());
  b.add_link(l);
  const auto m = b.finalize();
  // twisting about the limb (−y in the joint frame) is a twist, not a swing
  const SwingTwist t =
      joint_swing_twist(*m, 2, Quaternion(Eigen::AngleAxisd(0.05, -Vector3::UnitY())));
  EXPECT_NEAR(t.twist, 0.05, 1e-14);
  EXPECT_NEAR(std::hypot(t.a_y, t.a_z), 0.0, 1e-14);
  const SwingTwist s =
      joint_swing_twist(*m, 2, Quaternion(Eigen::AngleAxisd(0.4, Vector3::UnitX())));
  EXPECT_NEAR(std::hypot(s.a_y, s.a_z), std::sin(0.2), 1e-14);
}

// The quick test answers "inside" only for rotations the full test accepts, and it does answer
// for rotations well inside: a rotation by θ swings and twists by at most θ each.
TEST(SwingTwist, QuickInsideTestNeverAcceptsWhatTheFullTestRefuses) {
  ModelBuilder b;
  b.add_link(fixtures::box_link("root", "", 1, Vector3::Ones()));
  const std::vector<SphericalRange> ranges = {
      cone_range(kPi / 4, -0.5, 0.5),  // twist the narrower bound
      cone_range(kPi / 8, -1.0, 1.2),  // swing the narrower bound
      directional_range({0, kPi / 2, kPi, 1.5 * kPi}, {0.9, 0.4, 0.6, 0.3},
                        {-0.4, -0.2, -0.3, -0.1}, {0.3, 0.5, 0.2, 0.4}, -0.3, 0.3),
      cone_range(kPi / 4, 0.1, 0.6),  // the standard orientation is outside: no quick answer
  };
  for (size_t k = 0; k < ranges.size(); ++k) {
    LinkSpec l = fixtures::box_link("l" + std::to_string(k), "root", 1, Vector3::Ones());
    l.joint.type = JointType::kSpherical;
    l.joint.range = ranges[k];
    l.joint.range.frame = Quaternion(Eigen::AngleAxisd(0.3 * k, Vector3(1, 2, 3).normalized()));
    b.add_link(l);
  }
  const auto m = b.finalize();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int j = 2; j < m->njoints; ++j) {
    int quick = 0, small_refused = 0;
    for (int n = 0; n < 20000; ++n) {
      const double angle = 0.8 * std::abs(unit(rng));
      const Vector3 axis = Vector3(unit(rng), unit(rng), unit(rng)).normalized();
      // unnormalized and of either sign: the test must not depend on either
      const Quaternion q(Eigen::AngleAxisd(angle, axis));
      const double scale = (n % 2 ? -1.0 : 1.0) * (0.5 + std::abs(unit(rng)));
      const Quaternion r(scale * q.w(), scale * q.x(), scale * q.y(), scale * q.z());
      if (!joint_rotation_surely_inside(*m, j, r)) continue;
      ++quick;
      const RangeStatus full = check_joint_range(*m, j, joint_swing_twist(*m, j, r.normalized()));
      if (!full.inside) ++small_refused;
    }
    EXPECT_EQ(small_refused, 0) << "joint " << j;
    if (j < m->njoints - 1) {
      EXPECT_GT(quick, 1000) << "joint " << j << ": rotations well inside get a quick answer";
    } else {
      EXPECT_EQ(quick, 0) << "a range without the standard orientation has no quick answer";
    }
  }
  // the bound itself: 0.5 rad of twist is the first range's narrower limit
  const double just_inside = 0.5 * (1 - 1e-6), just_beyond = 0.5 * (1 + 1e-6);
  EXPECT_TRUE(joint_rotation_surely_inside(
      *m, 2, Quaternion(Eigen::AngleAxisd(just_inside, Vector3(1, 0, 0)))));
  EXPECT_FALSE(joint_rotation_surely_inside(
      *m, 2, Quaternion(Eigen::AngleAxisd(just_beyond, Vector3(1, 0, 0)))));
}

}  // namespace
