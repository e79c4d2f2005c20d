// Tests for ik/problem.hpp: ids, default levels, removal, typed access and whether the IK stage
// has anything to do.
#include "ik/problem.hpp"

#include <gtest/gtest.h>

namespace {

using namespace ik;
using core::Vector3;

TEST(Problem, IdsAreIncreasingAndNeverReused) {
  Problem p;
  const int a = p.add(LinkTask{.role = kDrag, .link = 3});
  const int b = p.add(LinkTask{.role = kPin, .link = 4});
  EXPECT_EQ(a, 1);
  EXPECT_EQ(b, 2);
  EXPECT_TRUE(p.remove(b));
  const int c = p.add(JointReferenceTask{.joint = 2});
  EXPECT_EQ(c, 3);  // not 2: an id stays unique after its task is gone
  p.clear();
  EXPECT_EQ(p.add(JointReferenceTask{.joint = 2}), 4);
}

TEST(Problem, RoleAndKindPickTheDefaultLevel) {
  Problem p;
  p.add(LinkTask{.role = kDrag, .link = 3});
  p.add(LinkTask{.role = kPin, .link = 4});
  p.add(JointReferenceTask{.joint = 2});
  p.add(Task(LinkTask{.role = kPin, .link = 5}), kTop);  // a pin promoted to level 1
  const auto& e = p.entries();
  ASSERT_EQ(e.size(), 4u);
  EXPECT_EQ(e[0].priority, kTop);
  EXPECT_EQ(e[1].priority, kLower);
  EXPECT_EQ(e[2].priority, kLower);
  EXPECT_EQ(e[3].priority, kTop);
  EXPECT_EQ(std::get<LinkTask>(e[3].task).role, kPin);
}

TEST(Problem, RemoveKeepsTheOthersInOrder) {
  Problem p;
  const int a = p.add(LinkTask{.link = 1});
  const int b = p.add(LinkTask{.link = 2});
  const int c = p.add(LinkTask{.link = 3});
  EXPECT_FALSE(p.remove(99));
  EXPECT_TRUE(p.remove(b));
  EXPECT_FALSE(p.remove(b));  // already gone
  ASSERT_EQ(p.entries().size(), 2u);
  EXPECT_EQ(p.entries()[0].id, a);
  EXPECT_EQ(p.entries()[1].id, c);
}

TEST(Problem, GetReturnsTheTaskOfThatKindForEditing) {
  Problem p;
  const int drag = p.add(LinkTask{.role = kDrag, .link = 3});
  const int ref = p.add(JointReferenceTask{.joint = 2, .q_ref = 0.5});
  LinkTask* d = p.get<LinkTask>(drag);
  ASSERT_NE(d, nullptr);
  d->target_W = Vector3(1, 2, 3);
  EXPECT_EQ(std::get<LinkTask>(p.entries()[0].task).target_W, Vector3(1, 2, 3));
  EXPECT_EQ(p.get<JointReferenceTask>(drag), nullptr);  // another kind
  EXPECT_EQ(p.get<LinkTask>(ref), nullptr);
  EXPECT_EQ(p.get<LinkTask>(42), nullptr);  // no such id
  ASSERT_NE(p.get<JointReferenceTask>(ref), nullptr);
  EXPECT_EQ(p.get<JointReferenceTask>(ref)->q_ref, 0.5);
}

TEST(Problem, ActiveOnlyWithADragOrAPin) {
  Problem p;
  EXPECT_FALSE(p.active());
  p.add(JointReferenceTask{.joint = 2});
  EXPECT_FALSE(p.active());  // references alone do not start the IK stage
  const int pin = p.add(LinkTask{.role = kPin, .link = 4});
  EXPECT_TRUE(p.active());
  p.remove(pin);
  EXPECT_FALSE(p.active());
  p.add(LinkTask{.role = kDrag, .link = 3});
  EXPECT_TRUE(p.active());
  p.clear();
  EXPECT_FALSE(p.active());
  EXPECT_TRUE(p.enforce_ranges);  // ranges are on unless turned off
}

}  // namespace
