// Tests for core/spatial.hpp.
#include "core/spatial.hpp"

#include <gtest/gtest.h>

#include <numbers>

namespace {

using namespace core;

Transform random_transform(int seed) {
  srand(seed);
  const Vector3 w = Vector3::Random() * 2.0;
  return {exp3(w), Vector3::Random()};
}

Matrix6 motion_cross_matrix(const Motion& m) {
  Matrix6 X = Matrix6::Zero();
  X.topLeftCorner<3, 3>() = skew(m.angular);
  X.bottomRightCorner<3, 3>() = skew(m.angular);
  X.bottomLeftCorner<3, 3>() = skew(m.linear);
  return X;
}

TEST(Spatial, MotionTransformMatchesItsMatrix) {
  const Transform X = random_transform(1);
  const Motion m{Vector3(0.3, -0.2, 0.9), Vector3(1, 2, -3)};
  EXPECT_TRUE(X.act(m).vector().isApprox(X.motion_matrix() * m.vector(), 1e-14));
  EXPECT_TRUE(X.act_inverse(X.act(m)).vector().isApprox(m.vector(), 1e-14));
}

TEST(Spatial, ForceTransformIsTheDualOfTheMotionTransform) {
  // power is frame independent: f_A · m_A = f_B · m_B
  const Transform X = random_transform(2);
  const Motion m{Vector3(0.1, 0.4, -0.5), Vector3(-1, 0.5, 2)};
  const Force f{Vector3(2, -1, 0.3), Vector3(0.2, 0.7, -0.4)};
  EXPECT_NEAR(X.act(f).dot(X.act(m)), f.dot(m), 1e-13);
  EXPECT_TRUE(X.act_inverse(X.act(f)).vector().isApprox(f.vector(), 1e-14));
}

TEST(Spatial, CrossProductsMatchFeatherstoneMatrices) {
  const Motion v{Vector3(0.3, -0.2, 0.9), Vector3(1, 2, -3)};
  const Motion m{Vector3(-0.5, 0.1, 0.2), Vector3(0.4, -0.6, 1.1)};
  const Force f{Vector3(2, -1, 0.3), Vector3(0.2, 0.7, -0.4)};
  EXPECT_TRUE(v.cross(m).vector().isApprox(motion_cross_matrix(v) * m.vector(), 1e-14));
  // crf(v) = -crm(v)ᵀ  (RBDA eq. 2.32)
  EXPECT_TRUE(
      cross(v, f).vector().isApprox(-motion_cross_matrix(v).transpose() * f.vector(), 1e-14));
}

TEST(Spatial, InertiaTransformMatchesCongruence) {
  // I_A = X_AB^{-T} I_B X_AB^{-1} with the 6x6 motion transform
  const Matrix3 I_c = Vector3(0.3, 0.2, 0.25).asDiagonal();
  const SpatialInertia I_B = SpatialInertia::from_com(2.5, Vector3(0.1, -0.2, 0.05), I_c);
  const Transform X = random_transform(3);
  const Matrix6 Xinv = X.inverse().motion_matrix();
  const Matrix6 expected = Xinv.transpose() * I_B.matrix() * Xinv;
  EXPECT_TRUE(I_B.transformed(X).matrix().isApprox(expected, 1e-12));
  EXPECT_TRUE(I_B.inertia_about_com().isApprox(I_c, 1e-12));
  const Motion v{Vector3(0.3, -0.2, 0.9), Vector3(1, 2, -3)};
  EXPECT_TRUE((I_B * v).vector().isApprox(I_B.matrix() * v.vector(), 1e-13));
}

TEST(Spatial, ExponentialAndLogarithmInvertEachOther) {
  for (double angle : {0.0, 1e-9, 1e-5, 0.3, 2.0, std::numbers::pi - 1e-7, std::numbers::pi}) {
    const Vector3 w = angle * Vector3(1, -2, 0.5).normalized();
    // at exactly π the rotation vectors w and −w describe the same rotation
    const Vector3 l = log3(exp3(w));
    const double err =
        angle == std::numbers::pi ? std::min((l - w).norm(), (l + w).norm()) : (l - w).norm();
    EXPECT_LT(err, 1e-9 * std::max(1.0, angle)) << angle;
    const Quaternion q = quaternion_exp(w);
    EXPECT_NEAR(q.norm(), 1.0, 1e-15);
    EXPECT_TRUE(q.toRotationMatrix().isApprox(exp3(w), 1e-12)) << angle;
    const Motion V{w, Vector3(0.4, -1.0, 2.0)};
    const Motion back = log6(exp6(V));
    if (angle < std::numbers::pi - 1e-3) {
      EXPECT_TRUE(back.vector().isApprox(V.vector(), 1e-9)) << angle;
    }
    EXPECT_TRUE(exp6(back).is_approx(exp6(V), 1e-9)) << angle;
  }
}

TEST(Spatial, ExponentialOfConstantTwistIsTheIntegral) {
  // X(t) = exp6(V t) satisfies Ẋ = X V̂: compare with many small steps
  const Motion V{Vector3(0.7, -0.3, 1.2), Vector3(0.5, 1.0, -0.2)};
  Transform X;
  const int n = 20000;
  for (int k = 0; k < n; ++k) X = X * exp6(V * (1.0 / n));
  EXPECT_TRUE(X.is_approx(exp6(V), 1e-10));
}

}  // namespace
