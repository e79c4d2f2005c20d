// Tests for core/model_builder.hpp: validation messages and the built tree.
#include "core/model_builder.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/fixtures/fixtures.hpp"

namespace {

using namespace core;
using fixtures::box_link;

// Expects finalize() to fail with a message containing every fragment.
void expect_error(const ModelBuilder& b, std::initializer_list<std::string> fragments) {
  try {
    b.finalize();
    FAIL() << "finalize() accepted an invalid model";
  } catch (const ModelError& e) {
    const std::string msg = e.what();
    for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << msg;
  }
}

ModelBuilder two_links() {
  ModelBuilder b("m");
  b.add_link(box_link("root", "", 1, Vector3(0.1, 0.1, 0.1)));
  LinkSpec l = box_link("arm", "root", 1, Vector3(0.1, 0.1, 0.1));
  l.joint.type = JointType::kRevolute;
  b.add_link(l);
  return b;
}

TEST(ModelBuilder, BuildsDepthFirstOrderWhateverTheInsertionOrder) {
  ModelBuilder b("m");
  LinkSpec c = box_link("c", "b", 1, Vector3(0.1, 0.1, 0.1));
  c.joint.type = JointType::kRevolute;
  b.add_link(c);
  LinkSpec d = box_link("d", "a", 1, Vector3(0.1, 0.1, 0.1));
  d.joint.type = JointType::kSpherical;
  b.add_link(d);
  LinkSpec bb = box_link("b", "a", 1, Vector3(0.1, 0.1, 0.1));
  bb.joint.type = JointType::kPrismatic;
  b.add_link(bb);
  LinkSpec a = box_link("a", "", 1, Vector3(0.1, 0.1, 0.1));
  a.joint.type = JointType::kFree;
  b.add_link(a);
  const auto m = b.finalize();
  ASSERT_EQ(m->njoints, 5);
  // a first, then its children in insertion order (d before b), each followed by its subtree
  EXPECT_EQ(m->link_name[1], "a");
  EXPECT_EQ(m->link_name[2], "d");
  EXPECT_EQ(m->link_name[3], "b");
  EXPECT_EQ(m->link_name[4], "c");
  for (int i = 1; i < m->njoints; ++i) EXPECT_LT(m->parent[i], i);
  EXPECT_EQ(m->subtree_end[1], 5);
  EXPECT_EQ(m->subtree_end[3], 5);
  EXPECT_EQ(m->subtree_end[2], 3);
  EXPECT_EQ(m->nq, 7 + 4 + 1 + 1);
  EXPECT_EQ(m->nv, 6 + 3 + 1 + 1);
  EXPECT_EQ(m->idx_v[4], 10);  // after free (6), spherical (3) and prismatic (1)
  EXPECT_EQ(m->joint_of_v[9], 3);
  EXPECT_EQ(m->joint_of_v[10], 4);
}

TEST(ModelBuilder, RejectsDuplicateNames) {
  ModelBuilder b = two_links();
  b.add_link(box_link("arm", "root", 1, Vector3(0.1, 0.1, 0.1)));
  expect_error(b, {"link 'arm'", "link names are unique", "joint 'arm'"});
}

TEST(ModelBuilder, RejectsMissingParentAndCycles) {
  ModelBuilder b = two_links();
  b.add_link(box_link("orphan", "nowhere", 1, Vector3(0.1, 0.1, 0.1)));
  b.add_link(box_link("x", "y", 1, Vector3(0.1, 0.1, 0.1)));
  b.add_link(box_link("y", "x", 1, Vector3(0.1, 0.1, 0.1)));
  b.add_link(box_link("self", "self", 1, Vector3(0.1, 0.1, 0.1)));
  expect_error(b,
               {"link 'orphan': parent link 'nowhere' does not exist", "link 'x': lies on a cycle",
                "link 'y': lies on a cycle", "link 'self': is its own parent"});
}

TEST(ModelBuilder, RequiresExactlyOneRoot) {
  ModelBuilder b = two_links();
  b.add_link(box_link("second_root", "", 1, Vector3(0.1, 0.1, 0.1)));
  expect_error(b, {"2 root links", "'root'", "'second_root'"});
  ModelBuilder none;
  none.add_link(box_link("a", "b", 1, Vector3(0.1, 0.1, 0.1)));
  none.add_link(box_link("b", "a", 1, Vector3(0.1, 0.1, 0.1)));
  expect_error(none, {"no root link"});
  expect_error(ModelBuilder(), {"no links"});
}

TEST(ModelBuilder, RejectsNonFiniteNumbers) {
  ModelBuilder b = two_links();
  b.link(1).joint.X_PJ.p.x() = NAN;
  b.link(0).com.y() = INFINITY;
  b.link(1).joint.limits.lower = NAN;
  expect_error(b, {"joint 'arm': placement is not a finite",
                   "link 'root': centre of mass is not finite", "joint 'arm': limit is NaN"});
}

TEST(ModelBuilder, RejectsUnphysicalInertia) {
  ModelBuilder b = two_links();
  b.link(0).mass = -1;
  b.link(1).I_com = Vector3(1.0, 0.1, 0.1).asDiagonal();  // 0.1 + 0.1 < 1
  expect_error(b, {"link 'root': mass -1 is negative", "link 'arm': principal moments",
                   "triangle inequality"});
  ModelBuilder c = two_links();
  c.link(1).I_com = Vector3(1.0, -0.5, 1.0).asDiagonal();
  expect_error(c, {"link 'arm': inertia is not positive semidefinite"});
  ModelBuilder d = two_links();
  d.link(1).I_com(0, 1) = 0.5;
  expect_error(d, {"link 'arm': inertia is not symmetric"});
}

TEST(ModelBuilder, RejectsInvertedLimitsAndBadRanges) {
  ModelBuilder b = two_links();
  b.link(1).joint.limits = {1.0, -1.0};
  LinkSpec s = box_link("ball", "arm", 1, Vector3(0.1, 0.1, 0.1));
  s.joint.type = JointType::kSpherical;
  s.joint.range.swing = {{0, 0}, {1.5, 0}, {0, 0.5}};
  s.joint.range.triangles = {{0, 1, 2}, {0, 1, 7}};
  s.joint.range.twist_lower = {0, 0, 1};
  s.joint.range.twist_upper = {0, 0, 0};
  b.add_link(s);
  expect_error(b, {"joint 'arm': lower limit 1 > upper limit -1", "outside the unit disk",
                   "range vertex 2: twist lower 1 > upper 0",
                   "range triangle 1 refers to a missing vertex"});
}

TEST(ModelBuilder, RejectsBadGeometry) {
  ModelBuilder b = two_links();
  Geometry g;
  g.shape = Geometry::Shape::kCapsule;
  g.radius = -0.1;
  b.link(1).collision.push_back(g);
  Geometry m;
  m.shape = Geometry::Shape::kMesh;
  b.link(1).visual.push_back(m);
  expect_error(b, {"link 'arm': collision shape 0 (capsule): radius must be > 0",
                   "visual shape 0 (mesh): mesh path is empty"});
}

TEST(ModelBuilder, CapsTheNumberOfLinks) {
  ModelBuilder b;
  for (int i = 0; i < kMaxLinks; ++i)
    b.add_link(box_link("l" + std::to_string(i), "", 1, Vector3::Ones()));
  EXPECT_THROW(b.add_link(box_link("one_too_many", "", 1, Vector3::Ones())), ModelError);
}

TEST(ModelBuilder, LongChainsBuildWithoutRecursion) {
  // 10,000 links deep: depth-first ordering must not recurse
  ModelBuilder b;
  for (int i = 0; i < kMaxLinks; ++i) {
    LinkSpec l =
        box_link("l" + std::to_string(i), i ? "l" + std::to_string(i - 1) : "", 1, Vector3::Ones());
    l.joint.type = JointType::kRevolute;
    b.add_link(l);
  }
  const auto m = b.finalize();
  EXPECT_EQ(m->nv, kMaxLinks);
  EXPECT_EQ(m->subtree_end[1], kMaxLinks + 1);
}

TEST(ModelBuilder, ModelsCompareEqualOnlyWhenIdentical) {
  const auto a = fixtures::branching_tree();
  const auto b = fixtures::branching_tree();
  EXPECT_TRUE(*a == *b);
  EXPECT_FALSE(*a == *fixtures::chain(3));
}

}  // namespace
