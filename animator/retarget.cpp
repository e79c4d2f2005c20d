#include "animator/retarget.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string_view>
#include <tuple>
#include <variant>

#include "animator/floor_contacts.hpp"
#include "animator/motion_editor.hpp"
#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/kinematics.hpp"
#include "core/swing_twist.hpp"
#include "ik/limits.hpp"
#include "ik/problem.hpp"
#include "ik/solver.hpp"

namespace animator {

namespace {

using core::Matrix3;
using core::Quaternion;
using core::Transform;
using core::Vector3;

// the leg length the contact thresholds are given for (m)
constexpr double kReferenceLegLength = 0.9;
// bones shorter than this give no direction (m)
constexpr double kMinBoneLength = 1e-4;
// a second bone fixes the twist when it leaves the first at more than asin(0.25) ≈ 14°
constexpr double kMinSecondBoneSine = 0.25;
// the retargeted joint values pull with this weight beside the pins (1): far below, so the pins
// hold where the two disagree (as in editing in motion)
constexpr double kSourcePoseWeight = 1e-3;
// a frame is solved again (up to kMaxRounds times) while a pin is further than this off (m)
constexpr double kPinTolerance = 5e-4;
constexpr int kMaxRounds = 20;
// a contact's pin beside the others when it cannot be held exactly: far above them, so hands and
// head give way first
constexpr double kSoftContactWeight = 100.0;
// ... and while a round still brings the pins this much closer in all (m): a pin the target cannot
// reach (a 34-DOF chest under a bending source) stops the rounds instead of dragging the root
constexpr double kPinProgress = 1e-4;
// rad of bone direction a radian of extra twist of the link above a hinge costs: only breaks ties
// (a straight limb), so the twist the source gives stays
constexpr double kHingeTwistCost = 1e-2;
// rad of range excess a radian of swivel of a limb must remove to be taken
constexpr double kSwivelCost = 0.5;

[[noreturn]] void refuse(const std::string& message) { throw std::invalid_argument(message); }

// the parts retargeting cannot do without: the hips place the root, the legs give the scale and
// carry the contacts
constexpr BodyPart kRequiredParts[] = {
    BodyPart::kHips,       BodyPart::kLeftThigh, BodyPart::kLeftShin, BodyPart::kLeftFoot,
    BodyPart::kRightThigh, BodyPart::kRightShin, BodyPart::kRightFoot};
// links pinned to where the bone directions put them (or to their contacts)
constexpr BodyPart kEffectorParts[] = {
    BodyPart::kLeftHand,  BodyPart::kRightHand, BodyPart::kHead,     BodyPart::kLeftFoot,
    BodyPart::kRightFoot, BodyPart::kLeftToes,  BodyPart::kRightToes};
constexpr BodyPart kContactParts[] = {BodyPart::kLeftFoot, BodyPart::kLeftToes,
                                      BodyPart::kRightFoot, BodyPart::kRightToes};

// left and right parts whose joints' difference is a body's lateral direction
constexpr std::pair<BodyPart, BodyPart> kLateralPairs[] = {
    {BodyPart::kLeftThigh, BodyPart::kRightThigh},
    {BodyPart::kLeftClavicle, BodyPart::kRightClavicle},
    {BodyPart::kLeftUpperArm, BodyPart::kRightUpperArm}};
// the floor is the height the feet's lowest points stay above in all but this share of frames
// (a capture's first frame may be a calibration pose below it)
constexpr double kFloorPercentile = 0.05;

bool moving(core::JointType t) { return t != core::JointType::kFixed; }

// an orthonormal frame whose x axis is along a and whose x–y plane holds b
Matrix3 frame_of(const Vector3& a, const Vector3& b) {
  const Vector3 x = a.normalized();
  const Vector3 z = x.cross(b).normalized();
  Matrix3 F;
  F.col(0) = x;
  F.col(1) = z.cross(x);
  F.col(2) = z;
  return F;
}

bool below(const core::Model& m, int ancestor, int link) {
  return link >= ancestor && link < m.subtree_end[ancestor];
}

// Per mapped target link t driven by source link s, the constant C_t of R_t = R_s · C_t:
// C_t = R_s0ᵀ · A · R_t0, A turning the target's rest bones out of t onto the source's.
std::vector<Matrix3> rest_alignment(const core::Model& S,
                                    const core::Model& T,
                                    const Correspondence& c) {
  core::Data ds(S), dt(T);
  core::forward_kinematics(S, ds, core::neutral_configuration(S));
  core::forward_kinematics(T, dt, core::neutral_configuration(T));
  // nearest mapped ancestor of every target link (0: none)
  std::vector<int> mapped_above(T.njoints, 0);
  for (int t = 1; t < T.njoints; ++t) {
    const int p = T.parent[t];
    mapped_above[t] = (p > 0 && c.source_of_target[p] >= 0) ? p : mapped_above[p];
  }
  std::vector<Matrix3> A(T.njoints, Matrix3::Identity()), C(T.njoints, Matrix3::Identity());
  for (int t = 1; t < T.njoints; ++t) {
    const int s = c.source_of_target[t];
    if (s < 0) continue;
    // the mapped links right below t (whose sources lie below s)
    std::vector<int> children;
    for (int u = t + 1; u < T.subtree_end[t]; ++u) {
      const int su = c.source_of_target[u];
      if (su >= 0 && mapped_above[u] == t && below(S, s, su)) children.push_back(u);
    }
    // a left and right pair among them (thighs, clavicles, upper arms) gives the lateral
    // direction, and the bones of the others start from between the pair: the hips' bone up the
    // spine starts at the hip centre, wherever each skeleton puts its root joint
    int left = -1, right = -1;
    for (auto [l, r] : kLateralPairs) {
      const int tl = c.target_of(l), tr = c.target_of(r);
      if (std::count(children.begin(), children.end(), tl) &&
          std::count(children.begin(), children.end(), tr)) {
        left = tl, right = tr;
        break;
      }
    }
    Vector3 base_t = dt.X_W[t].p, base_s = ds.X_W[s].p;
    if (left >= 0) {
      base_t = 0.5 * (dt.X_W[left].p + dt.X_W[right].p);
      base_s = 0.5 * (ds.X_W[c.source_of_target[left]].p + ds.X_W[c.source_of_target[right]].p);
    }
    std::vector<std::pair<Vector3, Vector3>> bones;  // (target, source) rest directions
    for (int u : children) {
      if (u == left || u == right) continue;
      const Vector3 bt = dt.X_W[u].p - base_t, bs = ds.X_W[c.source_of_target[u]].p - base_s;
      if (bt.norm() < kMinBoneLength || bs.norm() < kMinBoneLength) continue;
      bones.emplace_back(bt, bs);
    }
    if (left >= 0) {
      const Vector3 bt = dt.X_W[left].p - dt.X_W[right].p;
      const Vector3 bs = ds.X_W[c.source_of_target[left]].p - ds.X_W[c.source_of_target[right]].p;
      if (bt.norm() >= kMinBoneLength && bs.norm() >= kMinBoneLength) bones.emplace_back(bt, bs);
    }
    const auto second = std::find_if(
        bones.begin() + std::min<std::size_t>(1, bones.size()), bones.end(), [&](const auto& b) {
          const auto& [t0, s0] = bones.front();
          return t0.normalized().cross(b.first.normalized()).norm() > kMinSecondBoneSine &&
                 s0.normalized().cross(b.second.normalized()).norm() > kMinSecondBoneSine;
        });
    if (bones.empty()) {
      A[t] = A[mapped_above[t]];  // an end link turns as the bone above it
    } else if (second == bones.end()) {
      A[t] =
          Quaternion::FromTwoVectors(bones.front().first, bones.front().second).toRotationMatrix();
    } else {
      A[t] = frame_of(bones.front().second, second->second) *
             frame_of(bones.front().first, second->first).transpose();
    }
    C[t] = ds.X_W[s].R.transpose() * A[t] * dt.X_W[t].R;
  }
  return C;
}

double leg_length(const core::Data& rest, int thigh, int shin, int foot) {
  return (rest.X_W[shin].p - rest.X_W[thigh].p).norm() +
         (rest.X_W[foot].p - rest.X_W[shin].p).norm();
}

// the frames of each contact: runs of `in_contact` at least min_frames long
std::vector<std::pair<int, int>> runs(const std::vector<char>& in_contact, int min_frames) {
  std::vector<std::pair<int, int>> out;
  const int n = static_cast<int>(in_contact.size());
  for (int f = 0; f < n;) {
    if (!in_contact[f]) {
      ++f;
      continue;
    }
    int g = f;
    while (g + 1 < n && in_contact[g + 1]) ++g;
    if (g - f + 1 >= min_frames) out.emplace_back(f, g);
    f = g + 1;
  }
  return out;
}

// The longest windows of frames first..last in which the points stay within `diameter` of each
// other, at least min_frames long: the longest, then the same in what is left either side of it
// (less `gap` frames next to it)
std::vector<std::pair<int, int>> still_windows(
    const std::vector<Vector3>& p, int first, int last, double diameter, int min_frames, int gap) {
  if (last - first + 1 < min_frames) return {};
  int best_first = first, best_last = first - 1;
  for (int a = first, b = first; a <= last; ++a) {
    b = std::max(b, a);
    // extend b while the point b + 1 is within the diameter of all in a..b
    while (b + 1 <= last) {
      bool fits = true;
      for (int f = a; f <= b && fits; ++f) fits = (p[b + 1] - p[f]).norm() <= diameter;
      if (!fits) break;
      ++b;
    }
    if (b - a > best_last - best_first) best_first = a, best_last = b;
  }
  if (best_last - best_first + 1 < min_frames) return {};
  std::vector<std::pair<int, int>> out =
      still_windows(p, first, best_first - 1 - gap, diameter, min_frames, gap);
  out.emplace_back(best_first, best_last);
  for (auto w : still_windows(p, best_last + 1 + gap, last, diameter, min_frames, gap)) {
    out.push_back(w);
  }
  return out;
}

// The target's pose for one source frame, before the solver: mapped links take the source's
// world orientations through C; the other joints stay at their neutral values.
class PoseMapper {
 public:
  PoseMapper(const core::Model& T, const Correspondence& c, std::vector<Matrix3> C)
      : T_(T),
        c_(c),
        C_(std::move(C)),
        data_(T),
        R_desired_(T.njoints),
        R_actual_(T.njoints),
        p_ideal_(T.njoints),
        hinge_angle_(T.njoints) {
    // mapped hinges below a mapped ball joint that moves nothing else, with a mapped link below
    // them whose bone the hinge points
    for (int t = 2; t < T.njoints; ++t) {
      const int p = T.parent[t];
      if (T.joint_type[t] != core::JointType::kRevolute || c.source_of_target[t] < 0 ||
          c.source_of_target[p] < 0 || T.joint_type[p] != core::JointType::kSpherical) {
        continue;
      }
      int siblings = 0, below_link = -1;
      for (int u = p + 1; u < T.subtree_end[p]; ++u) {
        if (T.parent[u] == p && moving(T.joint_type[u])) ++siblings;
        if (T.parent[u] == t && below_link < 0 && c.source_of_target[u] >= 0) below_link = u;
      }
      if (siblings != 1 || below_link < 0) continue;
      const Vector3 parent_bone = T.X_PJ[t].p, bone = T.X_PJ[below_link].p;
      if (parent_bone.norm() < kMinBoneLength || bone.norm() < kMinBoneLength) continue;
      hinges_.push_back({t, p, below_link, parent_bone.normalized(), bone.normalized()});
    }
    // runs of unmapped moving links on the path from the hips to the head
    const int head = c.target_of(BodyPart::kHead);
    if (head > 0) {
      std::vector<int> path;
      for (int t = head; t > 0; t = T.parent[t]) path.insert(path.begin(), t);
      SpineRun run;
      for (int t : path) {
        if (c.source_of_target[t] >= 0) {
          if (!run.links.empty() && run.above > 0) {
            run.below = t;
            spine_runs_.push_back(run);
          }
          run = SpineRun{t, 0, {}};
        } else if (moving(T.joint_type[t])) {
          run.links.push_back(t);
        } else {
          run = SpineRun{};  // a fixed link breaks the run
        }
      }
    }
    for (int t = 2; t < T.njoints; ++t) {
      const int p = T.parent[t];
      if (T.joint_type[t] != core::JointType::kFixed || c.source_of_target[t] < 0 ||
          c.source_of_target[p] < 0 || T.joint_type[p] != core::JointType::kSpherical) {
        continue;
      }
      Weld w{t, p, {}};
      for (int u = t + 1; u < T.subtree_end[t]; ++u) {
        if (T.parent[u] == t && c.source_of_target[u] >= 0) w.below.push_back(u);
      }
      if (!w.below.empty()) welds_.push_back(w);
    }
  }

  /// The pose into q: joint values, then the root moved so the hip centre (between the two thigh
  /// joints) lands on hip_centre_W.
  void map(const std::vector<Transform>& X_Ws, const Vector3& hip_centre_W, Eigen::VectorXd& q) {
    q = core::neutral_configuration(T_);
    for (int t = 1; t < T_.njoints; ++t) {
      const int p = T_.parent[t], s = c_.source_of_target[t];
      const Matrix3 R_parent_desired = p > 0 ? R_desired_[p] : Matrix3::Identity();
      R_desired_[t] =
          s >= 0 ? Matrix3(X_Ws[s].R * C_[t]) : Matrix3(R_parent_desired * T_.X_PJ[t].R);
    }
    // a hinge (elbow, knee) turns its bone only in one plane: the link above it turns about its
    // own bone until the hinge's bone points where the source's does (a 3-DOF source elbow's bend
    // plane comes from the shoulder), so the limb's end lands where the bones put it
    // spine and neck joints the source has no match for share the turn between the mapped links
    // above and below them (a three-joint spine read on a two-joint one and back)
    for (const SpineRun& r : spine_runs_) {
      Matrix3 N = R_desired_[r.above];
      for (int u : r.links) N = N * T_.X_PJ[u].R;
      N = N * T_.X_PJ[r.below].R;
      const Quaternion E(Matrix3(R_desired_[r.below] * N.transpose()));
      Matrix3 R = R_desired_[r.above];
      const int k = static_cast<int>(r.links.size());
      for (int i = 0; i < k; ++i) {
        R = R * T_.X_PJ[r.links[i]].R;
        R_desired_[r.links[i]] =
            Quaternion::Identity().slerp(double(i + 1) / (k + 1), E).toRotationMatrix() * R;
      }
    }
    R_bones_ = R_desired_;  // where the source's bones point: the ideal positions
    // a link welded to a ball joint (a 34-DOF chest on the abdomen) cannot turn on its own: the
    // ball joint turns so the joints below the welded link come closest to where their bones
    // put them (Kabsch over the vectors from the ball joint)
    for (const Weld& w : welds_) {
      const Matrix3& Rp = R_desired_[w.parent];
      const Vector3 to_link = Rp * T_.X_PJ[w.link].p;
      Matrix3 H = Matrix3::Zero();
      for (int u : w.below) {
        const Vector3 a = Rp * (T_.X_PJ[w.link].p + T_.X_PJ[w.link].R * T_.X_PJ[u].p);
        const Vector3 b = to_link + R_desired_[w.link] * T_.X_PJ[u].p;
        H += a * b.transpose();
      }
      Eigen::JacobiSVD<Matrix3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Matrix3 D = Matrix3::Identity();
      D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
      R_desired_[w.parent] = svd.matrixV() * D * svd.matrixU().transpose() * Rp;
    }
    std::fill(hinge_angle_.begin(), hinge_angle_.end(), std::numeric_limits<double>::quiet_NaN());
    for (const Hinge& g : hinges_) {
      const auto [phi, theta] = hinge_twist(g);
      R_desired_[g.parent] = R_desired_[g.parent] * Eigen::AngleAxisd(phi, g.parent_bone);
      hinge_angle_[g.link] = theta;
      swivel_into_range(g);
    }
    for (int t = 1; t < T_.njoints; ++t) {
      const int p = T_.parent[t], s = c_.source_of_target[t];
      const Matrix3 R_base = (p > 0 ? R_actual_[p] : Matrix3::Identity()) * T_.X_PJ[t].R;
      R_actual_[t] = R_base;
      if (s < 0) continue;  // unmapped: the neutral joint value
      const Matrix3 R_J = R_base.transpose() * R_desired_[t];
      const int iq = T_.idx_q[t];
      switch (T_.joint_type[t]) {
        case core::JointType::kFree:
        case core::JointType::kSpherical: {
          const int iq_rot = T_.joint_type[t] == core::JointType::kFree ? iq + 3 : iq;
          core::set_quaternion_at(q, iq_rot, Quaternion(R_J).normalized());
          R_actual_[t] = R_desired_[t];
          break;
        }
        case core::JointType::kRevolute: {
          // a hinge below a turned link: the angle that points its bone; else the rotation
          // about the axis (the twist part of R_J)
          const Quaternion r(R_J);
          const double angle = std::isnan(hinge_angle_[t])
                                   ? 2.0 * std::atan2(r.vec().dot(T_.axis[t]), r.w())
                                   : hinge_angle_[t];
          q[iq] = std::remainder(angle, 2 * std::numbers::pi);
          R_actual_[t] = R_base * Eigen::AngleAxisd(q[iq], T_.axis[t]).toRotationMatrix();
          break;
        }
        default:
          break;
      }
    }
    // the root's position: move the hip centre where it belongs
    core::forward_kinematics(T_, data_, q);
    const int lt = c_.target_of(BodyPart::kLeftThigh), rt = c_.target_of(BodyPart::kRightThigh);
    const Vector3 now_W = 0.5 * (data_.X_W[lt].p + data_.X_W[rt].p);
    q.segment<3>(T_.idx_q[1]) += T_.X_PJ[1].R.transpose() * (hip_centre_W - now_W);
    core::forward_kinematics(T_, data_, q);
    // where each link would be if every joint could turn as the source's bones say
    p_ideal_[1] = data_.X_W[1].p;
    for (int t = 2; t < T_.njoints; ++t) {
      const int p = T_.parent[t];
      p_ideal_[t] = p_ideal_[p] + R_bones_[p] * T_.X_PJ[t].p;
    }
  }

  const std::vector<Vector3>& ideal_positions() const { return p_ideal_; }
  const core::Data& data() const { return data_; }  // kinematics of the last mapped pose

 private:
  struct SpineRun {
    int above = 0, below = 0;  // the mapped links around the run
    std::vector<int> links;    // unmapped, parent first
  };
  struct Weld {
    int link, parent;
    std::vector<int> below;  // mapped links right below the welded one
  };
  struct Hinge {
    int link, parent, below;
    Vector3 parent_bone;  // parent frame: toward the hinge
    Vector3 bone;         // hinge link frame: toward the link below
  };

  // The turn φ of the parent about its bone and the hinge angle θ (in the hinge's range) that
  // point the hinge's bone closest to the desired direction; of equally good turns, the smallest
  // (a straight limb leaves the parent's twist as the source has it).
  std::pair<double, double> hinge_twist(const Hinge& g) const {
    const Vector3 d_W = R_desired_[g.link] * g.bone;
    const Vector3 a = T_.axis[g.link];
    const core::JointLimits& L = T_.limits[g.link];
    auto evaluate = [&](double phi, double& theta) {
      const Matrix3 R_base = R_desired_[g.parent] *
                             Eigen::AngleAxisd(phi, g.parent_bone).toRotationMatrix() *
                             T_.X_PJ[g.link].R;
      const Vector3 v = R_base.transpose() * d_W;  // desired bone, hinge frame at θ = 0
      const Vector3 b_perp = g.bone - a * a.dot(g.bone), v_perp = v - a * a.dot(v);
      theta = std::atan2(a.dot(b_perp.cross(v_perp)), b_perp.dot(v_perp));
      theta = std::clamp(theta, L.lower, L.upper);
      const Vector3 b = Eigen::AngleAxisd(theta, a) * g.bone;
      return std::acos(std::clamp(b.dot(v), -1.0, 1.0)) + kHingeTwistCost * std::abs(phi);
    };
    // turns within a quarter turn either way: a half turn would bend a hyperextended knee
    // forward with the thigh turned round
    constexpr int kSteps = 36;
    double best_phi = 0, best_theta = 0, best = evaluate(0, best_theta);
    for (int k = -kSteps; k <= kSteps; ++k) {
      const double phi = 0.5 * std::numbers::pi * k / kSteps;
      double theta;
      const double e = evaluate(phi, theta);
      if (e < best) best = e, best_phi = phi, best_theta = theta;
    }
    // golden-section refinement within a grid step either side
    const double grid = 0.5 * std::numbers::pi / kSteps;
    double lo = best_phi - grid, hi = best_phi + grid;
    const double r = 0.5 * (std::sqrt(5.0) - 1.0);
    for (int it = 0; it < 40; ++it) {
      const double x1 = hi - r * (hi - lo), x2 = lo + r * (hi - lo);
      double t1, t2;
      if (evaluate(x1, t1) < evaluate(x2, t2)) {
        hi = x2;
      } else {
        lo = x1;
      }
    }
    double theta;
    const double phi = 0.5 * (lo + hi);
    if (evaluate(phi, theta) < best) best_phi = phi, best_theta = theta;
    return {best_phi, best_theta};
  }

  // A limb whose end joint (ankle, wrist) would leave its range with the end's orientation as the
  // source has it turns as a whole about the line from its root joint (hip, shoulder) to its end
  // joint: the swivel of hip–knee–ankle. The end stays where it is and keeps its orientation, the
  // knee or elbow points a little aside, and the turn the end's joint lacks moves into the root
  // joint: a foot turned out further than the ankle allows (as a source's 3-DOF knee, twisting,
  // leaves it) turns the hip out instead. The swivel minimizes the two joints' range excess plus
  // kSwivelCost per radian turned. (The root joint's rotation is taken from the desired
  // orientation of the link above; where that link hangs on a hinge, as an upper arm on a
  // clavicle does, the solver corrects the difference.)
  void swivel_into_range(const Hinge& g) {
    // the hinge's parent (the limb's root joint) is a ball joint below the free root, and the
    // end hangs on the hinge (see the constructor)
    const int end = g.below, root_parent = T_.parent[g.parent];
    if (T_.joint_type[end] != core::JointType::kSpherical || T_.spherical_range[end].empty()) {
      return;
    }
    const Matrix3 R_upper = R_desired_[g.parent];
    const Matrix3 R_lower =
        R_upper * T_.X_PJ[g.link].R * Eigen::AngleAxisd(hinge_angle_[g.link], T_.axis[g.link]);
    const Vector3 limb = R_upper * T_.X_PJ[g.link].p + R_lower * T_.X_PJ[end].p;
    if (limb.norm() < kMinBoneLength) return;
    const Vector3 axis = limb.normalized();
    const Matrix3 R_root_base = R_desired_[root_parent] * T_.X_PJ[g.parent].R;
    const bool root_ranged = !T_.spherical_range[g.parent].empty();
    auto excess = [&](double psi) {
      const Matrix3 turn = Eigen::AngleAxisd(psi, axis).toRotationMatrix();
      const Matrix3 R_end = (turn * R_lower * T_.X_PJ[end].R).transpose() * R_desired_[end];
      double v = core::joint_range_status(T_, end, Quaternion(R_end).normalized()).violation;
      if (root_ranged) {
        const Matrix3 R_root = R_root_base.transpose() * turn * R_upper;
        v += core::joint_range_status(T_, g.parent, Quaternion(R_root).normalized()).violation;
      }
      return v;
    };
    double best_psi = 0, best_cost = excess(0);
    if (best_cost == 0) return;
    // a grid of 2-degree steps over a quarter turn either way: a limb turns only as far as that
    // removes range excess, and a turn that removes little is not taken
    constexpr int kSteps = 45;
    for (int k = 1; k <= kSteps; ++k) {
      for (const int sign : {1, -1}) {
        const double psi = sign * 0.5 * std::numbers::pi * k / kSteps;
        const double cost = excess(psi) + kSwivelCost * std::abs(psi);
        if (cost < best_cost) best_cost = cost, best_psi = psi;
      }
    }
    if (best_psi == 0) return;
    R_desired_[g.parent] = Eigen::AngleAxisd(best_psi, axis) * R_upper;
  }

  const core::Model& T_;
  const Correspondence& c_;
  std::vector<Matrix3> C_;
  core::Data data_;
  std::vector<Matrix3> R_desired_, R_actual_;
  std::vector<Vector3> p_ideal_;
  std::vector<Hinge> hinges_;
  std::vector<Weld> welds_;
  std::vector<SpineRun> spine_runs_;
  std::vector<Matrix3> R_bones_;
  std::vector<double> hinge_angle_;  // per link: the hinge angle chosen, NaN for none
};

// the settings of editing in motion with more iterations per frame, each still a full step
ik::SolverSettings retarget_settings(double frame_time, int iterations) {
  ik::SolverSettings s = motion_edit_settings(frame_time);
  s.iterations = iterations;
  const double full = iterations / frame_time;
  s.pin_gain = full;
  s.reference_gain = full;
  s.drag_gain = full;
  return s;
}

}  // namespace

RetargetResult retarget(const core::Model& S,
                        const core::Clip& clip,
                        const core::Model& T,
                        const RetargetOptions& options) {
  if (clip.empty()) refuse("the clip has no frames (rule: a clip to retarget has frames)");
  if (const std::string bad = core::check_clip(S, clip); !bad.empty()) refuse(bad);
  if (T.njoints < 2 || T.joint_type[1] != core::JointType::kFree) {
    refuse("character '" + T.name +
           "': its root is not a free joint (rule: retargeting moves the root)");
  }
  if (options.iterations < 1 || options.first_frame_iterations < 1) {
    refuse("iterations: must be at least 1");
  }

  Correspondence c = guess_correspondence(S, T);
  apply_mapping(S, T, options.mapping, options.mapping_origin, c);
  for (BodyPart p : kRequiredParts) {
    if (c.target_of(p) < 0) {
      refuse("character '" + T.name + "': no link recognised as the " + to_string(p) +
             " (rule: the target needs hips and two legs; name them in the mapping)");
    }
    if (c.source_of(p) < 0) {
      refuse("clip of '" + S.name + "': no joint drives the " + to_string(p) + " (link '" +
             T.link_name[c.target_of(p)] +
             "') (rule: the clip needs recognisable hips and two legs; map them in the mapping)");
    }
  }

  RetargetResult result;
  RetargetReport& report = result.report;
  report.source_convention = c.source_parts.convention;
  report.target_convention = c.target_parts.convention;
  for (int t = 1; t < T.njoints; ++t) {
    if (c.source_of_target[t] >= 0) {
      report.mapping.emplace_back(c.source_of_target[t], t);
    } else if (moving(T.joint_type[t])) {
      report.unmapped_target.push_back(t);
    }
  }
  for (int s = 1; s < S.njoints; ++s) {
    if (c.target_of_source[s] < 0 && moving(S.joint_type[s])) report.unmapped_source.push_back(s);
  }

  // scale: the leg lengths at rest
  core::Data ds(S), dt(T);
  core::forward_kinematics(S, ds, core::neutral_configuration(S));
  core::forward_kinematics(T, dt, core::neutral_configuration(T));
  auto legs = [](const core::Data& d, auto link_of) {
    return 0.5 * (leg_length(d, link_of(BodyPart::kLeftThigh), link_of(BodyPart::kLeftShin),
                             link_of(BodyPart::kLeftFoot)) +
                  leg_length(d, link_of(BodyPart::kRightThigh), link_of(BodyPart::kRightShin),
                             link_of(BodyPart::kRightFoot)));
  };
  report.source_leg_length = legs(ds, [&](BodyPart p) { return c.source_of(p); });
  report.target_leg_length = legs(dt, [&](BodyPart p) { return c.target_of(p); });
  if (!(report.source_leg_length > kMinBoneLength && report.target_leg_length > kMinBoneLength)) {
    refuse("the legs have no length at rest (rule: thigh and shin joints must be apart)");
  }
  const double scale = report.scale = report.target_leg_length / report.source_leg_length;
  const double leg_units = report.source_leg_length / kReferenceLegLength;

  // the source's feet over the clip: lowest points (the floor) and joint positions
  const int n = clip.size();
  const double h = clip.frame_time;
  FloorContacts source_floor(S);
  struct Track {
    BodyPart part;
    int source, target;
    std::vector<double> height;
    std::vector<Vector3> p_W;
  };
  std::vector<Track> tracks;
  for (BodyPart p : kContactParts) {
    if (c.source_of(p) >= 0) tracks.push_back({p, c.source_of(p), c.target_of(p), {}, {}});
  }
  std::vector<std::vector<Transform>> source_poses(n);
  std::vector<double> lowest_per_frame(n, std::numeric_limits<double>::infinity());
  for (int f = 0; f < n; ++f) {
    core::forward_kinematics(S, ds, clip.frames[f]);
    source_poses[f] = ds.X_W;
    for (Track& k : tracks) {
      double low = source_floor.height(ds, k.source);
      if (!std::isfinite(low)) low = ds.X_W[k.source].p.y();  // no shapes: the joint
      k.height.push_back(low);
      k.p_W.push_back(ds.X_W[k.source].p);
      lowest_per_frame[f] = std::min(lowest_per_frame[f], low);
    }
  }
  {
    std::vector<double> sorted = lowest_per_frame;
    const auto nth = sorted.begin() + static_cast<long>(kFloorPercentile * (n - 1));
    std::nth_element(sorted.begin(), nth, sorted.end());
    report.source_floor = *nth;
  }

  // the retargeted poses and where the bones put each link
  PoseMapper mapper(T, c, rest_alignment(S, T, c));
  std::vector<Eigen::VectorXd> q_mapped(n);
  std::vector<std::vector<Vector3>> p_ideal(n);
  const int ls = c.source_of(BodyPart::kLeftThigh), rs = c.source_of(BodyPart::kRightThigh);
  for (int f = 0; f < n; ++f) {
    const Vector3 hip_W = 0.5 * (source_poses[f][ls].p + source_poses[f][rs].p);
    mapper.map(source_poses[f], scale * hip_W, q_mapped[f]);
    p_ideal[f] = mapper.ideal_positions();
  }

  // contacts: low and slow in the source, and within contact_stillness of where they are for the
  // whole contact (a foot rolling onto its toes is not planted); held on the target where the
  // bones put the link on average over the contact
  const int min_frames = std::max(1, static_cast<int>(std::ceil(options.min_contact_time / h)));
  const int blend_frames =
      std::max(1, static_cast<int>(std::lround(options.contact_blend_time / h)));
  struct Hold {
    int track, first, last;
    Vector3 p_W;
  };
  std::vector<Hold> holds;
  for (int k = 0; k < static_cast<int>(tracks.size()); ++k) {
    const Track& tr = tracks[k];
    std::vector<char> in_contact(n, 0);
    for (int f = 0; f < n; ++f) {
      const int a = std::max(0, f - 1), b = std::min(n - 1, f + 1);
      const double speed = b > a ? (tr.p_W[b] - tr.p_W[a]).norm() / ((b - a) * h) : 0.0;
      in_contact[f] = tr.height[f] - report.source_floor <= options.contact_height * leg_units &&
                      speed <= options.contact_speed * leg_units;
    }
    for (const auto& [run_first, run_last] : runs(in_contact, min_frames)) {
      for (const auto& [first, last] :
           still_windows(tr.p_W, run_first, run_last, options.contact_stillness * leg_units,
                         min_frames, blend_frames)) {
        Vector3 p = Vector3::Zero();
        for (int f = first; f <= last; ++f) p += p_ideal[f][tr.target];
        p /= last - first + 1;
        holds.push_back({k, first, last, p});
      }
    }
  }
  // a link of a foot whose other link is already held goes where that hold puts it (the foot is
  // rigid between the two), so the two pins agree
  std::sort(holds.begin(), holds.end(),
            [](const Hold& a, const Hold& b) { return a.first < b.first; });
  for (Hold& later : holds) {
    const int t = tracks[later.track].target;
    for (const Hold& held : holds) {
      const int u = tracks[held.track].target;
      if (&held == &later || held.first > later.first || held.last < later.first) continue;
      if (T.parent[t] != u && T.parent[u] != t) continue;
      later.p_W = held.p_W + (p_ideal[later.first][t] - p_ideal[later.first][u]);
      break;
    }
  }

  // the pins' targets, frame by frame: the free path eased onto each contact
  std::vector<int> effectors;
  for (BodyPart p : kEffectorParts) {
    const int t = c.target_of(p);
    if (t > 0 && std::find(effectors.begin(), effectors.end(), t) == effectors.end()) {
      effectors.push_back(t);
    }
  }
  // A link's hold moves it off its free path by an offset, eased in and out; the other link of the
  // same foot (foot and toes) moves by the same offset while it has no hold of its own, so the
  // two pins keep the foot's shape
  auto pin_target = [&](int f, int t) {
    Vector3 offset = Vector3::Zero();
    double best = 0;
    bool own = false;
    for (const Hold& hold : holds) {
      const int u = tracks[hold.track].target;
      if (u != t && T.parent[u] != t && T.parent[t] != u) continue;
      const int d = f < hold.first ? hold.first - f : (f > hold.last ? f - hold.last : 0);
      if (d >= blend_frames) continue;
      const double w = 0.5 * (1.0 + std::cos(std::numbers::pi * d / blend_frames));
      // the link's own hold first, then the larger weight
      if ((u == t && !own) || ((u == t) == own && w > best)) {
        // the hold's offset from the free path at the contact's nearer end
        const int end = f < hold.first ? hold.first : (f > hold.last ? hold.last : f);
        best = w;
        own = u == t;
        offset = w * (hold.p_W - p_ideal[end][u]);
      }
    }
    return Vector3(p_ideal[f][t] + offset);
  };

  auto in_hold = [&](int f, int t) {
    for (const Hold& hold : holds) {
      if (tracks[hold.track].target != t) continue;
      if (f > hold.first - blend_frames && f < hold.last + blend_frames) return true;
    }
    return false;
  };

  // solve every frame from the one before
  ik::Solver solver(T, retarget_settings(h, options.first_frame_iterations));
  core::Data data(T);
  ik::Problem problem;
  Eigen::VectorXd q = core::rest_configuration(T);
  result.clip.frame_time = h;
  result.clip.frames.reserve(n);
  std::vector<char> is_foot(T.njoints, 0);
  for (const Track& k : tracks) is_foot[k.target] = 1;
  Eigen::VectorXd q_start(T.nq);
  // Solves frame f from q_start into q: the contacts' pins on level 1 (hard: held exactly, the
  // joint ranges give way if they must) or with the other pins on level 3
  auto solve_frame = [&](int f, bool hard_contacts) {
    const Eigen::VectorXd& q_ref = q_mapped[f];
    problem.clear();
    core::forward_kinematics(T, dt, q_ref);
    problem.add(ik::LinkTask{.role = ik::kReference,
                             .link = 1,
                             .target_W = dt.X_W[1].p,
                             .target_R_W = Quaternion(dt.X_W[1].R),
                             .mode = ik::TaskMode::kPose,
                             .weight = kSourcePoseWeight});
    ik::add_joint_references(T, q_ref, problem);
    for (ik::Problem::Entry& e : problem.entries()) {
      if (auto* r = std::get_if<ik::JointReferenceTask>(&e.task)) r->weight = kSourcePoseWeight;
    }
    for (int t : effectors) {
      const bool contact = is_foot[t] && in_hold(f, t);
      problem.add(ik::LinkTask{.role = ik::kPin,
                               .link = t,
                               .target_W = pin_target(f, t),
                               .mode = ik::TaskMode::kPosition,
                               .weight = contact ? kSoftContactWeight : 1.0},
                  contact && hard_contacts ? ik::kTop : ik::kLower);
    }
    problem.enforce_ranges = true;
    q = q_start;
    // more steps while the pins come closer (a frame far from the one before, the first), until
    // they hold, stop coming closer or the rounds run out
    double last_total = std::numeric_limits<double>::infinity();
    for (int round = 0; round < kMaxRounds; ++round) {
      const ik::Report& step = solver.step(problem, data, q);
      if (step.status != ik::Report::Status::kOk) {
        refuse("frame " + std::to_string(f) + ": " + step.message);
      }
      double worst = 0, total = 0;
      for (const ik::TaskReport& tr : step.tasks) {
        if (std::string_view(tr.kind) != "pin") continue;
        worst = std::max(worst, tr.position_error);
        total += tr.position_error;
      }
      if (worst <= kPinTolerance || total > last_total - kPinProgress) break;
      last_total = total;
    }
  };
  for (int f = 0; f < n; ++f) {
    const Eigen::VectorXd& q_ref = q_mapped[f];
    // start from the retargeted pose, its joints inside their ranges: a 1-DOF joint clamped, a
    // ball joint outside its range as in the frame before (inside)
    q_start = q;
    q_start.segment<7>(T.idx_q[1]) = q_ref.segment<7>(T.idx_q[1]);
    for (int j = 2; j < T.njoints; ++j) {
      const int iq = T.idx_q[j];
      switch (T.joint_type[j]) {
        case core::JointType::kRevolute:
        case core::JointType::kPrismatic:
          q_start[iq] = std::clamp(q_ref[iq], T.limits[j].lower, T.limits[j].upper);
          break;
        case core::JointType::kSpherical: {
          const Quaternion r = core::quaternion_at(q_ref, iq);
          if (T.spherical_range[j].empty() || core::joint_range_status(T, j, r).inside) {
            core::set_quaternion_at(q_start, iq, r);
          }
          break;
        }
        default:
          break;
      }
    }
    solve_frame(f, true);
    // a contact held exactly that carries a joint out of its range is held as well as the range
    // allows instead, from there
    if (ik::max_range_violation(T, q) > 0.5 * kRangeTolerance) {
      const Eigen::VectorXd in_range = q_start;
      q_start = q;
      solve_frame(f, false);
      if (ik::max_range_violation(T, q) > 0.5 * kRangeTolerance) {
        q_start = in_range;  // the ranges pull back too slowly from there: start inside them
        solve_frame(f, false);
      }
    }
    if (f == 0) solver.set_settings(retarget_settings(h, options.iterations));
    result.clip.frames.push_back(q);
  }

  // what came out: ranges, contacts, effectors
  std::vector<std::vector<Vector3>> p_out(n, std::vector<Vector3>(T.njoints));
  for (int f = 0; f < n; ++f) {
    const double v = ik::max_range_violation(T, result.clip.frames[f]);
    report.max_range_violation = std::max(report.max_range_violation, v);
    if (v > kRangeTolerance) ++report.frames_out_of_range;
    core::forward_kinematics(T, data, result.clip.frames[f]);
    for (int t = 1; t < T.njoints; ++t) p_out[f][t] = data.X_W[t].p;
    for (int t : effectors) {
      report.max_effector_error =
          std::max(report.max_effector_error, (p_out[f][t] - pin_target(f, t)).norm());
    }
  }
  for (const Hold& hold : holds) {
    const Track& tr = tracks[hold.track];
    FootContact fc{
        .target_link = tr.target, .source_link = tr.source, .first = hold.first, .last = hold.last};
    for (int f = hold.first; f <= hold.last; ++f) {
      fc.slide = std::max(fc.slide, (p_out[f][tr.target] - p_out[hold.first][tr.target]).norm());
      fc.source_slide = std::max(fc.source_slide, scale * (tr.p_W[f] - tr.p_W[hold.first]).norm());
    }
    report.max_foot_slide = std::max(report.max_foot_slide, fc.slide);
    report.contacts.push_back(fc);
  }
  std::sort(report.contacts.begin(), report.contacts.end(),
            [](const FootContact& a, const FootContact& b) {
              return std::tie(a.first, a.target_link) < std::tie(b.first, b.target_link);
            });
  return result;
}

}  // namespace animator
