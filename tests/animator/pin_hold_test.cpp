// Hard pins hold on every frame of a drag (docs/ik.md, "Pin strength"): a session's pins are
// projected back after each solver step (ik::PinHold), on every bundled character.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "animator/session.hpp"
#include "core/kinematics.hpp"
#include "ik/limits.hpp"
#include "io/bundled_characters.hpp"

namespace {

using animator::Session;
using core::Vector3;

struct Gesture {
  const char* name;
  std::vector<int> pinned;
  int dragged = 0;
  Vector3 offset = Vector3::Zero();  // the drag target's travel, over half a second
};

// the largest pin error and range violation over every frame of the gesture: 30 frames of
// travel at 60 Hz, then 30 frames holding the target
struct Measured {
  double pin_error = 0;
  double range_violation = 0;
  double drag_error_at_end = 0;
};

Measured run_gesture(const std::shared_ptr<const core::Model>& model, const Gesture& g) {
  Session s(model, g.name);
  const core::Model& m = *model;
  const double violation_at_rest = ik::max_range_violation(m, s.q());
  std::vector<core::Transform> pinned;
  for (const int link : g.pinned) {
    s.pin(link, ik::TaskMode::kPose);
    pinned.push_back(s.kinematics().X_W[link]);
  }
  const Vector3 start = s.kinematics().X_W[g.dragged].p;
  s.drag_begin(g.dragged, start);
  Measured out;
  for (int frame = 1; frame <= 60; ++frame) {
    s.drag_move(start + g.offset * std::min(1.0, frame / 30.0));
    s.tick(1.0 / 60);
    for (std::size_t k = 0; k < g.pinned.size(); ++k) {
      const core::Transform& X = s.kinematics().X_W[g.pinned[k]];
      out.pin_error = std::max(out.pin_error, (X.p - pinned[k].p).norm());
    }
    EXPECT_TRUE(s.q().allFinite());
    out.range_violation =
        std::max(out.range_violation, ik::max_range_violation(m, s.q()) - violation_at_rest);
  }
  out.drag_error_at_end = (s.kinematics().X_W[g.dragged].p - start - g.offset).norm();
  s.drag_end();
  return out;
}

int link(const core::Model& m, const char* name) {
  const int i = m.link_index(name);
  EXPECT_GT(i, 0) << name;
  return i;
}

TEST(PinHold, HardPinsStayWithinAMillimetreOnEveryFrameOfEveryBundledCharacter) {
  for (const io::BundledCharacter& c : io::bundled_characters()) {
    const auto model = io::load_character(c.name).model;
    const core::Model& m = *model;
    std::vector<Gesture> gestures;
    if (m.link_index("l_foot") > 0) {
      const std::vector<int> feet = {link(m, "l_foot"), link(m, "r_foot")};
      // the squat, a hand reaching forward and up, the pelvis swung sideways
      gestures.push_back({"squat", feet, link(m, "pelvis"), Vector3(0, -0.25, 0)});
      gestures.push_back({"reach", feet, link(m, "r_hand"), Vector3(0, 0.3, 0.3)});
      gestures.push_back({"sway", feet, link(m, "pelvis"), Vector3(0.12, -0.05, 0)});
    } else {
      // a fixed-base arm: its middle link pinned, its tip moved sideways
      const int tip = m.njoints - 1;
      gestures.push_back({"tip", {m.njoints / 2}, tip, Vector3(0.1, 0.05, 0.1)});
    }
    for (const Gesture& g : gestures) {
      const Measured r = run_gesture(model, g);
      std::printf("%s %s: largest pin error %.3f mm, drag off by %.1f mm at the end\n",
                  c.name.c_str(), g.name, 1e3 * r.pin_error, 1e3 * r.drag_error_at_end);
      EXPECT_LT(r.pin_error, 1e-3) << c.name << ' ' << g.name;
      EXPECT_LT(r.range_violation, 1e-3) << c.name << ' ' << g.name << ": a joint left its range";
    }
  }
}

TEST(PinHold, ADragThePinsAndRangesAllowIsStillMet) {
  for (const char* name : {"human48", "human34"}) {
    const auto model = io::load_character(name).model;
    const core::Model& m = *model;
    const std::vector<int> feet = {link(m, "l_foot"), link(m, "r_foot")};
    for (const Gesture& g : {Gesture{"squat", feet, link(m, "pelvis"), Vector3(0, -0.12, 0)},
                             Gesture{"reach", feet, link(m, "r_hand"), Vector3(0, 0.3, 0.3)}}) {
      const Measured r = run_gesture(model, g);
      // half a second holding the target after it stopped
      EXPECT_LT(r.drag_error_at_end, 0.005) << name << ' ' << g.name << ": the target reached";
    }
  }
}

}  // namespace
