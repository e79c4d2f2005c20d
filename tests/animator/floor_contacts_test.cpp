// The floor in kinematic posing (animator/floor_contacts.hpp), measured on every frame of a
// gesture: a hand dragged with nothing pinned bends the figure and leaves the feet where they
// stand, a figure pushed down meets the floor instead of going through it, and with the floor
// switched off the same drags do what they did without it (so the tests can fail).
#include "animator/floor_contacts.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <vector>

#include "animator_fixtures.hpp"

namespace {

using animator::FloorContacts;
using animator::Session;
using animator_test::human;
using animator_test::position;
using core::Vector3;

Session session(bool floor) {
  Session s(human(), "human48");
  ik::SolverSettings settings = s.solver_settings();
  settings.floor = floor;
  s.set_solver_settings(settings);
  return s;
}

// the lowest collision point of the whole figure above the floor
double lowest_height(const Session& s, const FloorContacts& floor) {
  double lowest = std::numeric_limits<double>::infinity();
  for (int i = 1; i < s.model().njoints; ++i) {
    lowest = std::min(lowest, floor.height(s.kinematics(), i));
  }
  return lowest;
}

// per link, how low it may go: the floor, or its height now if lower (the rest pose has the feet
// a few millimetres into the floor)
std::vector<double> allowed_heights(const Session& s, const FloorContacts& floor) {
  std::vector<double> out(s.model().njoints, 0.0);
  for (int i = 1; i < s.model().njoints; ++i) {
    out[i] = std::min(0.0, floor.height(s.kinematics(), i));
  }
  return out;
}

// the deepest any link is below what it is allowed (negative: every link is above)
double deepest(const Session& s, const FloorContacts& floor, const std::vector<double>& allowed) {
  double out = -std::numeric_limits<double>::infinity();
  for (int i = 1; i < s.model().njoints; ++i) {
    out = std::max(out, allowed[i] - floor.height(s.kinematics(), i));
  }
  return out;
}

struct DragOutcome {
  double feet_drift = 0;  // largest distance of a foot from where it stood (m)
  double deepest = -std::numeric_limits<double>::infinity();  // below the floor, any frame
  Vector3 link_end = Vector3::Zero();                         // where the dragged link ended
  double deepest_at_rest = 0;  // below the floor once the figure has settled after the drag
};

// drags `link` by `offset` over one second at 60 frames/s, sampling every frame
DragOutcome drag(Session& s, const char* link, const Vector3& offset) {
  const FloorContacts floor(s.model());
  const char* feet[] = {"l_foot", "r_foot"};
  const Vector3 feet0[] = {position(s, feet[0]), position(s, feet[1])};
  const Vector3 start = position(s, link);
  const std::vector<double> allowed = allowed_heights(s, floor);
  DragOutcome g;
  s.drag_begin(s.model().link_index(link), start);
  for (int frame = 1; frame <= 60; ++frame) {
    s.drag_move(start + offset * std::min(1.0, frame / 45.0));
    s.tick(1.0 / 60);
    for (int k = 0; k < 2; ++k) {
      g.feet_drift = std::max(g.feet_drift, (position(s, feet[k]) - feet0[k]).norm());
    }
    g.deepest = std::max(g.deepest, deepest(s, floor, allowed));
  }
  g.link_end = position(s, link);
  s.drag_end();
  animator_test::run(s, 120);  // let go: the figure settles
  g.deepest_at_rest = deepest(s, floor, allowed);

  return g;
}

TEST(FloorContacts, ANewSessionStandsOnTheFloorWithTheFloorOn) {
  Session s(human(), "human48");
  EXPECT_TRUE(s.solver_settings().floor);
  const FloorContacts floor(s.model());
  EXPECT_NEAR(lowest_height(s, floor), 0.0, FloorContacts::kRestingReach)
      << "the figure's feet rest on the floor";
}

TEST(FloorContacts, AHandDraggedUpBendsTheFigureAndTheFeetStayWhereTheyStand) {
  // 0.5 m up and 0.3 m forward over 0.75 s, nothing pinned
  Session s = session(true);
  const Vector3 offset(0.0, 0.5, 0.3);
  const DragOutcome g = drag(s, "r_hand", offset);
  std::printf("hand up, floor on: feet drift %.2f mm, deepest %.2f mm\n", 1e3 * g.feet_drift,
              1e3 * g.deepest);
  EXPECT_LT(g.feet_drift, 0.001);
  EXPECT_LT(g.deepest, 0.001);
  EXPECT_LT(g.deepest_at_rest, 0.001);

  Session off = session(false);
  const DragOutcome free = drag(off, "r_hand", offset);
  std::printf("hand up, floor off: feet drift %.1f mm\n", 1e3 * free.feet_drift);
  EXPECT_GT(free.feet_drift, 0.05) << "without the floor the drag lifts the figure";
}

TEST(FloorContacts, AFigurePushedDownFoldsOntoTheFloorAndNotThroughIt) {
  // the pelvis pushed 0.6 m and 1.2 m down, out of reach: the figure folds onto the floor. A link
  // that meets the floor is caught after the step that carried it in, so within a frame it goes
  // at most as deep as the drag travels in one frame (1/45 of the push here)
  for (const double push : {0.6, 1.2}) {
    Session s = session(true);
    const DragOutcome g = drag(s, "pelvis", Vector3(0, -push, 0));
    std::printf(
        "pelvis %.1f m down, floor on: deepest %.2f mm in motion, %.2f mm at rest, feet drift "
        "%.2f mm, pelvis at %.3f m\n",
        push, 1e3 * g.deepest, 1e3 * g.deepest_at_rest, 1e3 * g.feet_drift, g.link_end.y());
    EXPECT_LT(g.deepest, push / 45);
    EXPECT_GT(g.link_end.y(), 0.0) << "the pelvis stays above the floor";
    // at rest: nothing below the floor after the reachable push; after the 1.2 m one the links
    // held on the floor over-constrain the folded figure and the pelvis rests a few mm in
    if (push < 1) {
      EXPECT_LT(g.deepest_at_rest, 0.001);
    }
    EXPECT_LT(g.deepest_at_rest, push / 45);

    Session off = session(false);
    const DragOutcome through = drag(off, "pelvis", Vector3(0, -push, 0));
    std::printf("pelvis %.1f m down, floor off: deepest %.1f mm\n", push, 1e3 * through.deepest);
    EXPECT_GT(through.deepest, 0.1) << "without the floor the figure sinks through it";
  }
}

TEST(FloorContacts, ADraggedFootLeavesTheFloorAndTheOtherStays) {
  Session s = session(true);
  const Vector3 l_foot0 = position(s, "l_foot");
  const DragOutcome g = drag(s, "r_foot", Vector3(0, 0.2, 0.1));
  EXPECT_GT(g.link_end.y() - position(s, "l_foot").y(), 0.1) << "the dragged foot is lifted";
  EXPECT_LT((position(s, "l_foot") - l_foot0).norm(), 0.001);
}

TEST(FloorContacts, UserPinsAreNotDoubledAndContactsEndWithTheGesture) {
  Session s = session(true);
  s.pin(s.model().link_index("l_foot"), ik::TaskMode::kPose);
  const DragOutcome g = drag(s, "r_hand", Vector3(0.2, 0.2, 0));
  EXPECT_LT(g.feet_drift, 0.001);
  animator_test::run(s, 120);  // settled
  EXPECT_FALSE(s.needs_tick());
}

}  // namespace

namespace {

TEST(FloorContacts, AnOutOfReachDragComesToRestAfterRelease) {
  // one foot pinned by the user, the other resting on the floor, a hand pulled 3 m sideways
  Session s = session(true);
  s.pin(s.model().link_index("l_foot"), ik::TaskMode::kPose);
  const Vector3 hand = position(s, "r_hand");
  s.drag_begin(s.model().link_index("r_hand"), hand);
  for (int k = 1; k <= 30; ++k) {
    s.drag_move(hand + Vector3(0.1 * k, 0, 0));
    s.tick(0.005);
  }
  s.drag_end();
  int ticks = 0;
  while (s.needs_tick() && ticks < 600) {
    s.tick(1.0 / 60);
    ++ticks;
  }
  std::printf("came to rest after %d ticks\n", ticks);
  EXPECT_LT(ticks, 600) << "the figure never came to rest";
}

}  // namespace
