// The floor in kinematic posing, without physics: no link's collision shapes go below y = 0, and
// links resting on the floor stay where they stand.
//
// Contacts work like automatic pins that exist for one gesture (a drag, or the settling after an
// edit). When it begins, each link resting on the floor (its lowest collision point within
// kRestingReach of it) is pinned where it is, unless the gesture drags it or the user pinned it;
// a link whose parent rests on the floor goes with its parent (a toe with its foot). During the
// gesture, a link that a step carried below the floor is pinned where it went in, lifted back
// onto it. A link that was already below the floor when the gesture began (a pose placed a little
// into it) is held from going deeper than it was, not pushed out. A resting box (a foot) is held in
// its whole pose, so it stays flat; any other shape (a knee, a hand) by its lowest point only, so
// it can roll on the floor. The pins go on the level the session's pins go on (ik::pin_priority),
// so with hard pins a drag that would lift a resting foot stops short instead.
#pragma once

#include <vector>

#include "animator/pin.hpp"
#include "core/data.hpp"
#include "core/model.hpp"
#include "sim/shapes.hpp"

namespace animator {

class FloorContacts {
 public:
  /// How close to the floor a link's lowest point is for it to rest on the floor (m).
  static constexpr double kRestingReach = 0.005;

  explicit FloorContacts(const core::Model& model);

  /// Starts a gesture in the posed `data`: pins every link resting on the floor except those
  /// whose `excluded` flag (indexed by link) is set.
  void begin(const core::Data& data, const std::vector<char>& excluded);
  /// After a solver step: pins each link that went below the floor (not excluded, not already
  /// held) back onto it. Returns whether any was added.
  bool catch_penetrations(const core::Data& data, const std::vector<char>& excluded);
  /// Ends the gesture: no contact is held.
  void clear();

  const std::vector<Pin>& pins() const { return pins_; }
  /// Height of link `link`'s lowest collision point above the floor (+inf without shapes).
  double height(const core::Data& data, int link) const;
  /// How far that point is below where the gesture lets it go (the floor, or its height when
  /// the gesture began if that was lower); negative when it is above.
  double depth(const core::Data& data, int link) const;

 private:
  struct Lowest {
    double height;
    core::Vector3 point_W;
    bool box;
  };
  Lowest lowest(const core::Data& data, int link) const;
  void hold(const core::Data& data, int link, const Lowest& low, double lift);

  const core::Model& model_;
  sim::BodyShapes shapes_;
  std::vector<char> movable_;  // a moving joint lies between the link and the world
  std::vector<char> held_;     // the link has a contact pin
  std::vector<double> floor_;  // per link: 0, or its height when the gesture began if lower
  std::vector<Pin> pins_;
};

}  // namespace animator
