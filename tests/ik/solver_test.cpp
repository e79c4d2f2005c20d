// Tests for ik/solver.hpp: exactness of level 1, the null-space property, convergence,
// determinism and allocation-free steps (the hard cases are in hard_cases_test.cpp).
#include "ik/solver.hpp"

#include <gtest/gtest.h>

#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "io/bundled_characters.hpp"
#include "tests/fixtures/allocation_counter.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using namespace ik;
using core::Vector3;

// While alive, an Eigen heap allocation fails an assertion (builds without NDEBUG, as the
// project's Release flags): fixtures::AllocationCounter sees operator new only, and Eigen
// allocates with malloc.
struct NoEigenMalloc {
  NoEigenMalloc() { Eigen::internal::set_is_malloc_allowed(false); }
  ~NoEigenMalloc() { Eigen::internal::set_is_malloc_allowed(true); }
  NoEigenMalloc(const NoEigenMalloc&) = delete;
  NoEigenMalloc& operator=(const NoEigenMalloc&) = delete;
};

struct Scene {
  std::shared_ptr<const core::Model> model = fixtures::branching_tree();
  core::Data data{*model};
  Eigen::VectorXd q = core::neutral_configuration(*model);
  Vector3 world(const std::string& link, const Vector3& p = Vector3::Zero()) {
    core::forward_kinematics(*model, data, q);
    return data.X_W[model->link_index(link)] * p;
  }
};

TEST(Solver, ReachableDragConvergesAndPinsHold) {
  Scene s;
  const int hand = s.model->link_index("hand");
  const int wrist = s.model->link_index("wrist");
  Problem problem;
  const int drag = problem.add(LinkTask{
      .role = kDrag, .link = hand, .target_W = s.world("hand") + Vector3(0.05, 0.05, 0.02)});
  problem.add(LinkTask{.role = kPin, .link = wrist, .target_W = s.world("wrist")});
  Solver solver(*s.model);
  for (int frame = 0; frame < 60; ++frame) solver.step(problem, s.data, s.q);
  const Report& r = solver.report();
  ASSERT_EQ(r.tasks.size(), 2u);
  EXPECT_EQ(r.tasks[0].id, drag);
  EXPECT_LT(r.tasks[0].position_error, 1e-6);
  EXPECT_LT(r.tasks[1].position_error, 1e-3);
  EXPECT_TRUE(r.tasks[0].satisfied);
  EXPECT_EQ(r.top_rank, 3);
  EXPECT_FALSE(r.top_damped);
}

TEST(Solver, LowerLevelTasksDoNotDisturbTheTopLevel) {
  // the top-level velocity residual is the same with and without a conflicting lower task
  Scene s;
  const int hand = s.model->link_index("hand");
  const Vector3 target = s.world("hand") + Vector3(0.02, -0.01, 0.03);
  auto top_velocity_error = [&](bool with_pin) {
    Scene t;
    Problem p;
    p.add(LinkTask{.role = kDrag, .link = hand, .target_W = target});
    if (with_pin)
      p.add(LinkTask{
          .role = kPin, .link = hand, .target_W = target + Vector3(1, 1, 1), .weight = 100});
    SolverSettings settings;
    settings.dt = 1e-4;  // nearly linear step: the top level must be met to first order
    Solver solver(*t.model, settings);
    solver.step(p, t.data, t.q);
    return (t.world("hand") - target).norm();
  };
  const double without = top_velocity_error(false), with = top_velocity_error(true);
  EXPECT_NEAR(with, without, 1e-9);
}

TEST(Solver, IdenticalInputGivesBitIdenticalOutput) {
  auto run = [] {
    Scene s;
    Problem p;
    p.add(LinkTask{.role = kDrag,
                   .link = s.model->link_index("hand"),
                   .target_W = Vector3(0.5, 0.3, 0.2),
                   .mode = TaskMode::kPosition});
    p.add(LinkTask{.role = kPin,
                   .link = s.model->link_index("yaw"),
                   .target_W = s.world("yaw"),
                   .mode = TaskMode::kPose});
    Solver solver(*s.model);
    for (int k = 0; k < 30; ++k) solver.step(p, s.data, s.q);
    return s.q;
  };
  const Eigen::VectorXd a = run(), b = run();
  EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * a.size()), 0);
}

TEST(Solver, StepsDoNotAllocateOnceSized) {
  Scene s;
  Problem p;
  p.add(LinkTask{
      .role = kDrag, .link = s.model->link_index("hand"), .target_W = Vector3(0.3, 0.1, 0.2)});
  p.add(LinkTask{.role = kPin,
                 .link = s.model->link_index("wrist"),
                 .target_W = s.world("wrist"),
                 .mode = TaskMode::kPose});
  p.add(JointReferenceTask{.joint = s.model->link_index("ball"), .weight = 0.1});
  p.add(JointReferenceTask{.joint = s.model->link_index("hinge"), .q_ref = 0.3, .weight = 0.1});
  for (const DampingSchedule schedule :
       {DampingSchedule::kResidual, DampingSchedule::kConstant, DampingSchedule::kManipulability}) {
    SolverSettings settings;
    settings.damping_schedule = schedule;
    Solver solver(*s.model, settings);
    solver.step(p, s.data, s.q);
    fixtures::AllocationCounter allocations;
    {
      const NoEigenMalloc no_eigen_malloc;
      for (int k = 0; k < 10; ++k) solver.step(p, s.data, s.q);
    }
    EXPECT_EQ(allocations.count(), 0) << to_string(schedule);
  }
}

TEST(Solver, DampedTopLevelStepsDoNotAllocate) {
  // a fixed-root arm dragged far out of reach: J1 loses rank and level 1 is damped through an
  // eigen-decomposition, which must reuse its buffers too
  const auto model = io::load_character("arm7").model;
  core::Data data(*model);
  Eigen::VectorXd q = core::neutral_configuration(*model);
  core::forward_kinematics(*model, data, q);
  const int tip = model->njoints - 1;
  const Vector3 base = data.X_W[1].p;
  const Vector3 far = base + (data.X_W[tip].p - base).normalized() * 5.0;
  Problem p;
  p.add(LinkTask{.role = kDrag, .link = tip, .target_W = far});
  Solver solver(*model);
  solver.step(p, data, q);  // warm-up: sizes the workspace
  ASSERT_TRUE(solver.report().top_damped);
  // a second drag (6 level-1 rows) is seen once, then comes and goes
  const LinkTask second{.role = kDrag, .link = tip - 1, .target_W = far + Vector3(0, 1, 0)};
  const int id = p.add(second);
  solver.step(p, data, q);
  p.remove(id);
  fixtures::AllocationCounter allocations;
  int damped = 0;
  {
    const NoEigenMalloc no_eigen_malloc;
    for (int k = 0; k < 10; ++k) {
      damped += solver.step(p, data, q).top_damped;
      const int added = p.add(second);
      solver.step(p, data, q);
      p.remove(added);
    }
  }
  EXPECT_EQ(damped, 10);
  EXPECT_EQ(allocations.count(), 0);
  EXPECT_TRUE(q.allFinite());
}

TEST(Solver, RejectsBadSettings) {
  SolverSettings s;
  EXPECT_EQ(validate(s), "");
  s.dt = -1;
  EXPECT_NE(validate(s).find("dt"), std::string::npos);
  s = {};
  s.pin_gain = NAN;
  EXPECT_NE(validate(s).find("pin_gain"), std::string::npos);
}

}  // namespace
