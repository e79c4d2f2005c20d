#include "core/human_figure.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/model_builder.hpp"
#include "core/swing_twist.hpp"

namespace core {

namespace {

constexpr double deg(double d) { return d * std::numbers::pi / 180.0; }

// ---------------------------------------------------------------------------------------------
// Segment data: de Leva (1996), "Adjustments to Zatsiorsky–Seluyanov's segment inertia
// parameters", J. Biomech. 29(9):1223–1230, male values (Table 4, and de Leva's alternative rows
// referred to CERV for the head and the upper trunk). Lengths in metres at de Leva's mean
// stature of 1.741 m; mass as a fraction of body mass; CM and radii of gyration as fractions of
// the segment length, the CM measured from the first (origin) landmark. Radii: about the
// sagittal (antero-posterior) axis, the transverse (medio-lateral) axis and the longitudinal
// axis. For the foot, whose longitudinal axis is antero-posterior, "sagittal" is the axis in the
// sagittal plane across the foot (vertical at the neutral pose).
// ---------------------------------------------------------------------------------------------
struct DeLevaSegment {
  double length;
  double mass;
  double com;
  double r_sag;
  double r_trans;
  double r_long;
};

constexpr double kDeLevaStature = 1.741;
// head and neck, VERT → CERV (equivalently VERT → MIDG 0.2033 m, CM 59.76 %, r 36.2/37.6/31.2 %)
constexpr DeLevaSegment kHeadNeck{0.2429, 0.0694, 0.5002, 0.303, 0.315, 0.261};
// upper trunk, CERV → XYPH (equivalently SUPR → XYPH 0.1707 m, CM 29.99 %, r 71.6/45.4/65.9 %)
constexpr DeLevaSegment kUpperTrunk{0.2421, 0.1596, 0.5066, 0.505, 0.320, 0.465};
// middle trunk, XYPH → OMPH
constexpr DeLevaSegment kMiddleTrunk{0.2155, 0.1633, 0.4502, 0.482, 0.383, 0.468};
// lower trunk, OMPH → MIDH (mid-point of the hip joint centres)
constexpr DeLevaSegment kLowerTrunk{0.1457, 0.1117, 0.6115, 0.615, 0.551, 0.587};
// upper arm SJC → EJC, forearm EJC → WJC, hand WJC → MET3
constexpr DeLevaSegment kUpperArm{0.2817, 0.0271, 0.5772, 0.285, 0.269, 0.158};
constexpr DeLevaSegment kForearm{0.2689, 0.0162, 0.4574, 0.276, 0.265, 0.121};
constexpr DeLevaSegment kHand{0.0862, 0.0061, 0.7900, 0.628, 0.513, 0.401};
// thigh HJC → KJC, shank KJC → LMAL, foot HEEL → TTIP
constexpr DeLevaSegment kThigh{0.4222, 0.1416, 0.4095, 0.329, 0.329, 0.149};
constexpr DeLevaSegment kShank{0.4340, 0.0433, 0.4459, 0.255, 0.249, 0.103};
constexpr DeLevaSegment kFoot{0.2581, 0.0137, 0.4415, 0.257, 0.245, 0.124};
// CERV lies above SUPR by the difference of de Leva's two upper-trunk lengths
constexpr double kCervToSupr = 0.2421 - 0.1707;

// ---------------------------------------------------------------------------------------------
// Choices where de Leva is silent (fractions of stature H unless noted); docs/human-figure.md.
// ---------------------------------------------------------------------------------------------
// ankle joint above the sole: Drillis & Contini (1966), as drawn in Winter, "Biomechanics and
// Motor Control of Human Movement", Fig. 4.1. The hip height then comes out at 0.531 H
// (Winter: 0.530 H).
constexpr double kAnkleHeight = 0.039;
// hip joint centres ±0.05 H from the midline (≈ 17.5 cm apart at 1.75 m)
constexpr double kHipHalfWidth = 0.05;
// shoulder joint centres ±0.10 H from the midline, 0.067 H below CERV (0.81 H above the sole)
constexpr double kShoulderHalfWidth = 0.10;
constexpr double kShoulderBelowCerv = 0.067;
// sternoclavicular joints at SUPR level, ±0.014 H from the midline, 0.03 H in front of the
// coronal plane that holds the spine line, the hip and the shoulder joint centres
constexpr double kSternoclavicularHalfWidth = 0.014;
constexpr double kSternoclavicularForward = 0.03;
// the head–neck column (CERV to vertex) gets what the stature leaves after the ankle, the legs
// and the trunk; its lower 40 % is the neck (CERV to the atlanto-occipital joint)
constexpr double kNeckShareOfColumn = 0.4;
// mass splits of de Leva segments (fractions of the segment's mass, or of body mass)
constexpr double kNeckShareOfHeadNeck = 0.2;  // neck 20 %, head 80 % of head + neck
constexpr double kClavicleMass = 0.008;       // each shoulder girdle link, of body mass (from UPT)
// toes 14 % (≈ 1/7) of the foot; with 20 % the remainder (de Leva's foot is more compact than a
// uniform rod) breaks the triangle inequality
constexpr double kToesShareOfFoot = 0.14;
// foot layout along the foot (fractions of de Leva's foot length HEEL → TTIP)
constexpr double kHeelBehindAnkle = 0.22;
constexpr double kMtpFromHeel = 0.73;
// heights above the sole (fractions of the ankle height)
constexpr double kFootComHeight = 0.45;
constexpr double kMtpHeight = 0.35;
constexpr double kToeThickness = 0.30;
constexpr double kFootBoxHeight = 0.80;
constexpr double kFootWidth = 0.055;  // Winter Fig. 4.1
// hand: fingertip 0.108 H from the wrist (Winter Fig. 4.1), breadth 0.05 H, thickness 0.016 H
constexpr double kHandLength = 0.108;
constexpr double kHandBreadth = 0.05;
constexpr double kHandThickness = 0.016;

// collision capsule radii (fractions of H); the head is a sphere touching the vertex
constexpr double kHeadRadius = 0.055;
constexpr double kNeckRadius = 0.03;
constexpr double kClavicleRadius = 0.018;
constexpr double kUpperArmRadius = 0.025;
constexpr double kForearmRadius = 0.02;
constexpr double kThighRadius = 0.04;
constexpr double kShankRadius = 0.028;
constexpr double kPelvisRadius = 0.05, kPelvisHalfLength = 0.03;
constexpr double kAbdomenRadius = 0.055, kAbdomenHalfLength = 0.03;
constexpr double kChestRadius = 0.06, kChestHalfLength = 0.04;

// IK weights: the relative cost of moving a joint (per unit of its velocity coordinates) in the
// weighted least-squares IK; 1 is a limb joint, larger values make the solver prefer other joints.
constexpr double kWeightRoot = 2.0;
constexpr double kWeightSpine = 4.0;
constexpr double kWeightNeck = 2.0;
constexpr double kWeightClavicle = 4.0;
constexpr double kWeightLimb = 1.0;
constexpr double kWeightWristAnkle = 1.5;
constexpr double kWeightHip = 1.5;
constexpr double kWeightToes = 3.0;

// ---------------------------------------------------------------------------------------------
// small geometry and inertia helpers
// ---------------------------------------------------------------------------------------------

// rotational inertia about the COM from radii of gyration (fractions of L) along x, y, z
Matrix3 gyration_inertia(double m, double L, double rx, double ry, double rz) {
  return m * Vector3(rx * rx * L * L, ry * ry * L * L, rz * rz * L * L).asDiagonal();
}

// de Leva radii on our axes for a segment whose long axis is vertical: x = transverse
// (medio-lateral), y = longitudinal, z = sagittal (antero-posterior)
Matrix3 vertical_segment_inertia(double m, double L, const DeLevaSegment& d) {
  return gyration_inertia(m, L, d.r_trans, d.r_long, d.r_sag);
}

// solid cylinder of radius r and length L along unit u, about its centre
Matrix3 cylinder_inertia(double m, double r, double L, const Vector3& u) {
  const Matrix3 uu = u * u.transpose();
  return m * (3 * r * r + L * L) / 12.0 * (Matrix3::Identity() - uu) + m * r * r / 2.0 * uu;
}

// solid box with full extents `size`, about its centre
Matrix3 box_inertia(double m, const Vector3& size) {
  const Vector3 q = size.cwiseProduct(size);
  return m / 12.0 * Vector3(q.y() + q.z(), q.x() + q.z(), q.x() + q.y()).asDiagonal();
}

// a rigid body in some reference frame: mass, COM and inertia about the COM
struct Body {
  double mass = 0;
  Vector3 com = Vector3::Zero();
  Matrix3 I_com = Matrix3::Zero();
};

// what remains of `whole` after removing `parts` (all in the same frame): mass, first moment
// and inertia about the frame origin subtract; the builder rejects a non-physical remainder
Body remainder(const Body& whole, const std::vector<Body>& parts) {
  SpatialInertia rest = SpatialInertia::from_com(whole.mass, whole.com, whole.I_com);
  for (const Body& p : parts) {
    const SpatialInertia s = SpatialInertia::from_com(p.mass, p.com, p.I_com);
    rest.mass -= s.mass;
    rest.h -= s.h;
    rest.I_O -= s.I_O;
  }
  Body out;
  out.mass = rest.mass;
  out.com = rest.com();
  out.I_com = rest.inertia_about_com();
  out.I_com = 0.5 * (out.I_com + out.I_com.transpose());
  return out;
}

// rotation whose z axis is d (exact for axis-aligned d)
Matrix3 frame_with_z(const Vector3& d) {
  const Vector3 z = d.normalized();
  const Vector3 t = std::abs(z.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY();
  const Vector3 x = (t - z * z.dot(t)).normalized();
  Matrix3 R;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return R;
}

Geometry capsule(const Vector3& p0, const Vector3& p1, double radius) {
  Geometry g;
  g.shape = Geometry::Shape::kCapsule;
  g.X_LinkShape = {frame_with_z(p1 - p0), 0.5 * (p0 + p1)};
  g.radius = radius;
  g.length = (p1 - p0).norm();
  return g;
}

Geometry sphere(const Vector3& centre, double radius) {
  Geometry g;
  g.shape = Geometry::Shape::kSphere;
  g.X_LinkShape = Transform::from_translation(centre);
  g.radius = radius;
  return g;
}

Geometry box(const Vector3& centre, const Vector3& size) {
  Geometry g;
  g.shape = Geometry::Shape::kBox;
  g.X_LinkShape = Transform::from_translation(centre);
  g.size = size;
  return g;
}

// ---------------------------------------------------------------------------------------------
// ranges
// ---------------------------------------------------------------------------------------------

// range frame in joint coordinates: x = the nominal link direction, y = the direction that
// ψ = 0 tilts x toward; ψ = 90° tilts toward x × y
Quaternion range_frame(const Vector3& x, const Vector3& y) {
  Matrix3 R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = x.cross(y);
  return Quaternion(R).normalized();
}

// joint rotation that swings the nominal direction by phi toward ψ, after a twist
Quaternion pose_in_range(const Quaternion& frame, double psi, double phi, double twist) {
  const Eigen::Vector2d a = swing_toward(psi, phi);
  return (frame * from_swing_twist(a.x(), a.y(), twist) * frame.conjugate()).normalized();
}

// A fan whose swing limit follows an ellipse in each quadrant between the limits toward ψ = 0,
// 90°, 180° and 270°, with one twist interval; n directions, ψ_k = 2πk/n.
SphericalRange elliptic_range(const Quaternion& frame,
                              double at0,
                              double at90,
                              double at180,
                              double at270,
                              double twist_lower,
                              double twist_upper,
                              int n = 16) {
  std::vector<double> psi, swing, lo, hi;
  for (int k = 0; k < n; ++k) {
    const double p = 2 * std::numbers::pi * k / n;
    const double c = std::cos(p), s = std::sin(p);
    const double a = c >= 0 ? at0 : at180;
    const double b = s >= 0 ? at90 : at270;
    psi.push_back(p);
    swing.push_back(1.0 / std::sqrt((c / a) * (c / a) + (s / b) * (s / b)));
    lo.push_back(twist_lower);
    hi.push_back(twist_upper);
  }
  SphericalRange r = directional_range(psi, swing, lo, hi, twist_lower, twist_upper);
  r.frame = frame;
  return r;
}

// a clinical limit toward one direction of the swing plane (degrees)
struct Anchor {
  double psi;
  double swing;
  double twist_lower;
  double twist_upper;
};

// A fan through anchor directions (ψ increasing over the full circle), each interval split into
// `subdivisions` steps with swing and twist limits interpolated linearly in ψ.
SphericalRange anchored_range(const Quaternion& frame,
                              const std::vector<Anchor>& anchors,
                              double centre_twist_lower,
                              double centre_twist_upper,
                              int subdivisions) {
  std::vector<double> psi, swing, lo, hi;
  const int n = static_cast<int>(anchors.size());
  for (int k = 0; k < n; ++k) {
    const Anchor& a = anchors[k];
    const Anchor& b = anchors[(k + 1) % n];
    const double b_psi = k + 1 < n ? b.psi : b.psi + 360.0;
    for (int j = 0; j < subdivisions; ++j) {
      const double t = static_cast<double>(j) / subdivisions;
      psi.push_back(deg(a.psi + t * (b_psi - a.psi)));
      swing.push_back(deg(a.swing + t * (b.swing - a.swing)));
      lo.push_back(deg(a.twist_lower + t * (b.twist_lower - a.twist_lower)));
      hi.push_back(deg(a.twist_upper + t * (b.twist_upper - a.twist_upper)));
    }
  }
  SphericalRange r =
      directional_range(psi, swing, lo, hi, deg(centre_twist_lower), deg(centre_twist_upper));
  r.frame = frame;
  return r;
}

// ---------------------------------------------------------------------------------------------
// mirroring the left side into the right side (reflection M = diag(−1, 1, 1))
// ---------------------------------------------------------------------------------------------

// a function, not a global: it is used during other translation units' static initialization
Matrix3 mirror_matrix() { return Vector3(-1, 1, 1).asDiagonal(); }

std::string mirror_name(const std::string& s) {
  if (s.rfind("l_", 0) == 0) return "r_" + s.substr(2);
  return s;
}

std::string mirror_display_name(const std::string& s) {
  if (s.rfind("Left ", 0) == 0) return "Right " + s.substr(5);
  return s;
}

Transform mirror(const Transform& X) {
  const Matrix3 M = mirror_matrix();
  return {M * X.R * M, M * X.p};
}

// M R M for a rotation given as a quaternion: (w, x, y, z) → (w, x, −y, −z)
Quaternion mirror(const Quaternion& q) { return Quaternion(q.w(), q.x(), -q.y(), -q.z()); }

// The mirrored range: its frame is M F N with N = diag(1, 1, −1), so a left rotation Q in range
// coordinates becomes N Q N on the right: (a_y, a_z, γ) → (−a_y, a_z, −γ).
SphericalRange mirror(const SphericalRange& r) {
  SphericalRange out = r;
  const Matrix3 N = Vector3(1, 1, -1).asDiagonal();
  out.frame = Quaternion(Matrix3(mirror_matrix() * r.frame.toRotationMatrix() * N)).normalized();
  for (size_t k = 0; k < r.swing.size(); ++k) {
    out.swing[k] = Eigen::Vector2d(-r.swing[k].x(), r.swing[k].y());
    out.twist_lower[k] = -r.twist_upper[k];
    out.twist_upper[k] = -r.twist_lower[k];
  }
  return out;
}

LinkSpec mirror(const LinkSpec& l) {
  LinkSpec r = l;
  r.name = mirror_name(l.name);
  r.parent = mirror_name(l.parent);
  r.display_name = mirror_display_name(l.display_name);
  r.joint.name = mirror_name(l.joint.name);
  r.joint.X_PJ = mirror(l.joint.X_PJ);
  // an axial vector reflects as −M a
  const Matrix3 M = mirror_matrix();
  r.joint.axis = -(M * l.joint.axis);
  r.joint.range = l.joint.range.empty() ? l.joint.range : mirror(l.joint.range);
  r.joint.standard_orientation = mirror(l.joint.standard_orientation);
  r.com = M * l.com;
  r.I_com = M * l.I_com * M;
  for (Geometry& g : r.collision) g.X_LinkShape = mirror(g.X_LinkShape);
  for (Geometry& g : r.visual) g.X_LinkShape = mirror(g.X_LinkShape);
  return r;
}

// ---------------------------------------------------------------------------------------------
// the figure
// ---------------------------------------------------------------------------------------------

class FigureBuilder {
 public:
  explicit FigureBuilder(const HumanFigureOptions& o)
      : H_(o.height), M_(o.mass), s_(o.height / kDeLevaStature), full_(o.dof == 48) {
    // vertical layout: sole, ankle, knee, hip (MIDH), OMPH, XYPH, CERV, vertex
    h_ankle_ = kAnkleHeight * H_;
    L_shank_ = kShank.length * s_;
    L_thigh_ = kThigh.length * s_;
    L_pelvis_ = kLowerTrunk.length * s_;
    L_abdomen_ = kMiddleTrunk.length * s_;
    L_chest_ = kUpperTrunk.length * s_;
    L_column_ = H_ - (h_ankle_ + L_shank_ + L_thigh_ + L_pelvis_ + L_abdomen_ + L_chest_);
    L_neck_ = kNeckShareOfColumn * L_column_;
    L_head_ = L_column_ - L_neck_;
    L_uarm_ = kUpperArm.length * s_;
    L_farm_ = kForearm.length * s_;
    L_hand_ = kHand.length * s_;
    L_foot_ = kFoot.length * s_;
  }

  std::shared_ptr<const Model> build() {
    ModelBuilder b(full_ ? "human48" : "human34");
    b.add_link(pelvis());
    b.add_link(abdomen());
    b.add_link(chest());
    b.add_link(neck());
    b.add_link(head());
    for (const LinkSpec& l :
         {clavicle(), upper_arm(), forearm(), hand(), thigh(), shank(), foot(), toes()}) {
      b.add_link(l);
      b.add_link(mirror(l));
    }
    return b.finalize();
  }

 private:
  static LinkSpec link(const std::string& name,
                       const std::string& parent,
                       const std::string& display,
                       const std::string& joint,
                       JointType type,
                       const Vector3& p_ParentJoint,
                       double ik_weight) {
    LinkSpec l;
    l.name = name;
    l.parent = parent;
    l.display_name = display;
    l.joint.name = joint;
    l.joint.type = type;
    l.joint.X_PJ = Transform::from_translation(p_ParentJoint);
    l.joint.ik_weight = ik_weight;
    return l;
  }

  // type of a joint that exists only in the 48-DOF figure
  JointType only48(JointType t) const { return full_ ? t : JointType::kFixed; }

  static void set_body(LinkSpec& l, const Body& body) {
    l.mass = body.mass;
    l.com = body.com;
    l.I_com = body.I_com;
  }

  static void set_geometry(LinkSpec& l, std::vector<Geometry> shapes) {
    l.collision = shapes;
    l.visual = std::move(shapes);
  }

  // a de Leva segment hanging from its joint along −y, CM measured from the joint
  Body hanging_segment(const DeLevaSegment& d, double L) const {
    const double m = d.mass * M_;
    return {m, Vector3(0, -d.com * L, 0), vertical_segment_inertia(m, L, d)};
  }

  // a de Leva trunk segment rising from its joint along +y, CM measured from its upper end
  Body trunk_segment(const DeLevaSegment& d, double L) const {
    const double m = d.mass * M_;
    return {m, Vector3(0, (1.0 - d.com) * L, 0), vertical_segment_inertia(m, L, d)};
  }

  LinkSpec pelvis() const {
    // free root at the mid-point of the hip joint centres (de Leva's MIDH)
    LinkSpec l = link("pelvis", "", "Pelvis", "root", JointType::kFree,
                      Vector3(0, h_ankle_ + L_shank_ + L_thigh_, 0), kWeightRoot);
    set_body(l, trunk_segment(kLowerTrunk, L_pelvis_));
    const double y = 0.3 * L_pelvis_;
    set_geometry(l, {capsule(Vector3(-kPelvisHalfLength * H_, y, 0),
                             Vector3(kPelvisHalfLength * H_, y, 0), kPelvisRadius * H_)});
    return l;
  }

  LinkSpec abdomen() const {
    // lumbar joint at OMPH
    LinkSpec l = link("abdomen", "pelvis", "Abdomen", "lumbar", JointType::kSpherical,
                      Vector3(0, L_pelvis_, 0), kWeightSpine);
    set_body(l, trunk_segment(kMiddleTrunk, L_abdomen_));
    // 48 DOF: the lumbar share of the thoracolumbar range; 34 DOF: all of it (AAOS 1965:
    // flexion 80°, extension 25°, lateral bending 35°, rotation 45°)
    const Quaternion F = range_frame(Vector3::UnitY(), Vector3::UnitZ());
    l.joint.range = full_
                        ? elliptic_range(F, deg(50), deg(20), deg(15), deg(20), deg(-10), deg(10))
                        : elliptic_range(F, deg(80), deg(35), deg(25), deg(35), deg(-45), deg(45));
    const double y = 0.5 * L_abdomen_;
    set_geometry(l, {capsule(Vector3(-kAbdomenHalfLength * H_, y, 0),
                             Vector3(kAbdomenHalfLength * H_, y, 0), kAbdomenRadius * H_)});
    return l;
  }

  // sternoclavicular joint and shoulder joint centre in the chest frame (left side)
  Vector3 p_ChestSternoclavicular() const {
    return {kSternoclavicularHalfWidth * H_, L_chest_ - kCervToSupr * s_,
            kSternoclavicularForward * H_};
  }
  Vector3 p_ChestShoulder() const {
    return {kShoulderHalfWidth * H_, L_chest_ - kShoulderBelowCerv * H_, 0};
  }

  // the left shoulder-girdle link as a uniform rod from the sternoclavicular joint to the
  // shoulder joint centre, in the chest frame
  Body clavicle_in_chest(double side) const {
    const Vector3 a = Vector3(side, 1, 1).cwiseProduct(p_ChestSternoclavicular());
    const Vector3 c = Vector3(side, 1, 1).cwiseProduct(p_ChestShoulder());
    const double m = kClavicleMass * M_;
    return {m, 0.5 * (a + c),
            cylinder_inertia(m, kClavicleRadius * H_, (c - a).norm(), (c - a).normalized())};
  }

  LinkSpec chest() const {
    // thoracic joint at XYPH; the chest is de Leva's upper trunk less both shoulder-girdle links
    LinkSpec l = link("chest", "abdomen", "Chest", "thoracic", only48(JointType::kSpherical),
                      Vector3(0, L_abdomen_, 0), kWeightSpine);
    set_body(l, remainder(trunk_segment(kUpperTrunk, L_chest_),
                          {clavicle_in_chest(1.0), clavicle_in_chest(-1.0)}));
    if (full_) {
      // thoracic share of the thoracolumbar range (AAOS totals split after Kapandji)
      const Quaternion F = range_frame(Vector3::UnitY(), Vector3::UnitZ());
      l.joint.range = elliptic_range(F, deg(30), deg(15), deg(10), deg(15), deg(-35), deg(35));
    }
    const double y = 0.45 * L_chest_;
    set_geometry(l, {capsule(Vector3(-kChestHalfLength * H_, y, 0),
                             Vector3(kChestHalfLength * H_, y, 0), kChestRadius * H_)});
    return l;
  }

  // de Leva's head + neck in the neck frame: CM 50.02 % of VERT → CERV below the vertex,
  // radii from de Leva's (scaled) segment length
  Body head_neck_in_neck() const {
    const double L = kHeadNeck.length * s_;
    const double m = kHeadNeck.mass * M_;
    return {m, Vector3(0, L_column_ - kHeadNeck.com * L, 0),
            vertical_segment_inertia(m, L, kHeadNeck)};
  }

  Body neck_body() const {
    const double m = kNeckShareOfHeadNeck * kHeadNeck.mass * M_;
    return {m, Vector3(0, 0.5 * L_neck_, 0),
            cylinder_inertia(m, kNeckRadius * H_, L_neck_, Vector3::UnitY())};
  }

  LinkSpec neck() const {
    // cervical joint at CERV (C7/T1)
    LinkSpec l = link("neck", "chest", "Neck", "neck", JointType::kSpherical,
                      Vector3(0, L_chest_, 0), kWeightNeck);
    set_body(l, neck_body());
    // cervical spine (AAOS 1965): flexion 45°, extension 45°, lateral bending 45°, rotation 60°;
    // 48 DOF leaves 10° flexion and 15° extension to the head nod (White & Panjabi: C0–C1)
    const Quaternion F = range_frame(Vector3::UnitY(), Vector3::UnitZ());
    l.joint.range = full_
                        ? elliptic_range(F, deg(35), deg(45), deg(30), deg(45), deg(-60), deg(60))
                        : elliptic_range(F, deg(45), deg(45), deg(45), deg(45), deg(-60), deg(60));
    set_geometry(l, {capsule(Vector3::Zero(), Vector3(0, L_neck_, 0), kNeckRadius * H_)});
    return l;
  }

  LinkSpec head() const {
    // atlanto-occipital joint: nod about +x (flexion positive)
    LinkSpec l = link("head", "neck", "Head", "nod", only48(JointType::kRevolute),
                      Vector3(0, L_neck_, 0), kWeightNeck);
    l.joint.axis = Vector3::UnitX();
    if (full_) l.joint.limits = {deg(-15), deg(10)};
    Body b = remainder(head_neck_in_neck(), {neck_body()});
    b.com -= Vector3(0, L_neck_, 0);
    set_body(l, b);
    set_geometry(l, {sphere(Vector3(0, L_head_ - kHeadRadius * H_, 0), kHeadRadius * H_)});
    return l;
  }

  LinkSpec clavicle() const {
    // shoulder-girdle elevation about the antero-posterior axis (elevation positive)
    LinkSpec l = link("l_clav", "chest", "Left clavicle", "l_clavicle",
                      only48(JointType::kRevolute), p_ChestSternoclavicular(), kWeightClavicle);
    l.joint.axis = Vector3::UnitZ();
    // Inman et al. (1944): ≈ 30–36° of clavicle elevation over full arm elevation; depression
    // ≈ 10° (Kapandji)
    if (full_) l.joint.limits = {deg(-10), deg(30)};
    Body b = clavicle_in_chest(1.0);
    b.com -= p_ChestSternoclavicular();
    set_body(l, b);
    set_geometry(l, {capsule(Vector3::Zero(), p_ChestShoulder() - p_ChestSternoclavicular(),
                             kClavicleRadius * H_)});
    return l;
  }

  LinkSpec upper_arm() const {
    LinkSpec l = link("l_uarm", "l_clav", "Left upper arm", "l_shoulder", JointType::kSpherical,
                      p_ChestShoulder() - p_ChestSternoclavicular(), kWeightLimb);
    set_body(l, hanging_segment(kUpperArm, L_uarm_));
    // nominal direction down the arm; ψ = 0 flexion (forward), 90° adduction (medial), 180°
    // extension, 270° abduction; twist positive = internal rotation. AAOS (1965): flexion 180°,
    // extension 60°, abduction 180°, internal rotation 70°, external 90° (at 90° abduction);
    // Kapandji: adduction 30–45° (with flexion), horizontal adduction ≈ 135°, horizontal
    // abduction ≈ 45°, external rotation ≈ 80° with the arm at the side. The glenohumeral joint
    // gets elevation up to 150°; the shoulder girdle (l_clav) supplies the last 30° (Inman),
    // and the singular direction (arm straight up, swing 180°) stays 30° outside the range.
    const Quaternion F = range_frame(-Vector3::UnitY(), Vector3::UnitZ());
    l.joint.range = anchored_range(F,
                                   {{0, 150, -60, 50},     // flexion
                                    {45, 100, -45, 70},    // horizontal adduction (cross-body)
                                    {90, 30, -70, 80},     // adduction
                                    {135, 40, -50, 90},    // extension + adduction (behind back)
                                    {180, 60, -60, 80},    // extension
                                    {225, 95, -90, 45},    // horizontal abduction
                                    {270, 150, -90, 30},   // abduction
                                    {315, 150, -80, 40}},  // scapular-plane elevation
                                   -80, 70, 3);
    // relaxed: 10° abduction, 5° flexion
    l.joint.standard_orientation =
        pose_in_range(F, std::atan2(-10.0, 5.0), deg(std::hypot(10.0, 5.0)), 0.0);
    set_geometry(l, {capsule(Vector3::Zero(), Vector3(0, -L_uarm_, 0), kUpperArmRadius * H_)});
    return l;
  }

  LinkSpec forearm() const {
    // elbow flexion: the forearm swings forward, rotation about −x
    LinkSpec l = link("l_farm", "l_uarm", "Left forearm", "l_elbow", JointType::kRevolute,
                      Vector3(0, -L_uarm_, 0), kWeightLimb);
    l.joint.axis = -Vector3::UnitX();
    // AAOS (1965): flexion 150°; a few degrees of hyperextension are common (Kapandji)
    l.joint.limits = {deg(-5), deg(150)};
    set_body(l, hanging_segment(kForearm, L_farm_));
    set_geometry(l, {capsule(Vector3::Zero(), Vector3(0, -L_farm_, 0), kForearmRadius * H_)});
    return l;
  }

  LinkSpec hand() const {
    LinkSpec l = link("l_hand", "l_farm", "Left hand", "l_wrist", only48(JointType::kSpherical),
                      Vector3(0, -L_farm_, 0), kWeightWristAnkle);
    set_body(l, hanging_segment(kHand, L_hand_));
    if (full_) {
      // palm faces the thigh (−x for the left hand), thumb forward. ψ = 0 radial deviation,
      // 90° flexion (palm side), 180° ulnar deviation, 270° extension; the twist is forearm
      // pronation (+) / supination (−), lumped at the wrist. AAOS (1965): flexion 80°,
      // extension 70°, radial 20°, ulnar 30°, pronation 80°, supination 80°.
      const Quaternion F = range_frame(-Vector3::UnitY(), Vector3::UnitZ());
      l.joint.range = elliptic_range(F, deg(20), deg(80), deg(30), deg(70), deg(-80), deg(80));
      l.joint.standard_orientation = pose_in_range(F, deg(90), deg(10), 0.0);  // 10° flexion
    }
    const double len = kHandLength * H_;
    set_geometry(
        l, {box(Vector3(0, -0.5 * len, 0), Vector3(kHandThickness * H_, len, kHandBreadth * H_))});
    return l;
  }

  LinkSpec thigh() const {
    LinkSpec l = link("l_thigh", "pelvis", "Left thigh", "l_hip", JointType::kSpherical,
                      Vector3(kHipHalfWidth * H_, 0, 0), kWeightHip);
    set_body(l, hanging_segment(kThigh, L_thigh_));
    // nominal direction down the thigh; ψ as at the shoulder; twist positive = internal
    // rotation. AAOS (1965): flexion 120°, extension 30°, abduction 45°, adduction 30°,
    // internal and external rotation 45°; rotation narrows in extension (Kapandji: the
    // iliofemoral ligament tightens). The singular direction (thigh straight up) is 60° outside.
    const Quaternion F = range_frame(-Vector3::UnitY(), Vector3::UnitZ());
    l.joint.range = anchored_range(F,
                                   {{0, 120, -45, 45},    // flexion
                                    {45, 90, -40, 45},    // flexion + adduction
                                    {90, 30, -45, 40},    // adduction
                                    {135, 20, -40, 35},   // extension + adduction
                                    {180, 30, -35, 35},   // extension
                                    {225, 35, -45, 35},   // extension + abduction
                                    {270, 45, -45, 40},   // abduction
                                    {315, 90, -50, 45}},  // flexion + abduction
                                   -45, 45, 3);
    // relaxed: 5° flexion, 3° abduction, 5° external rotation
    l.joint.standard_orientation =
        pose_in_range(F, std::atan2(-3.0, 5.0), deg(std::hypot(3.0, 5.0)), deg(-5));
    set_geometry(l, {capsule(Vector3::Zero(), Vector3(0, -L_thigh_, 0), kThighRadius * H_)});
    return l;
  }

  LinkSpec shank() const {
    // knee flexion: the shank swings backward, rotation about +x
    LinkSpec l = link("l_shank", "l_thigh", "Left shank", "l_knee", JointType::kRevolute,
                      Vector3(0, -L_thigh_, 0), kWeightLimb);
    l.joint.axis = Vector3::UnitX();
    // AAOS (1965): flexion 135°; up to 5° hyperextension
    l.joint.limits = {deg(-5), deg(135)};
    set_body(l, hanging_segment(kShank, L_shank_));
    set_geometry(l, {capsule(Vector3::Zero(), Vector3(0, -L_shank_, 0), kShankRadius * H_)});
    return l;
  }

  // positions in the foot frame (the ankle joint centre)
  double z_heel() const { return -kHeelBehindAnkle * L_foot_; }
  Vector3 p_FootMtp() const {
    return {0, -(1.0 - kMtpHeight) * h_ankle_, z_heel() + kMtpFromHeel * L_foot_};
  }
  double toes_length() const { return (1.0 - kMtpFromHeel) * L_foot_; }

  // de Leva's foot in the foot frame; its radii on our axes: x transverse, y sagittal, z long
  Body whole_foot() const {
    const double m = kFoot.mass * M_;
    return {m, Vector3(0, -(1.0 - kFootComHeight) * h_ankle_, z_heel() + kFoot.com * L_foot_),
            gyration_inertia(m, L_foot_, kFoot.r_trans, kFoot.r_sag, kFoot.r_long)};
  }

  // the toes as a solid box from the MTP joint to the toe tip, resting on the sole
  Vector3 toes_size() const { return {kFootWidth * H_, kToeThickness * h_ankle_, toes_length()}; }
  Body toes_in_foot() const {
    const double m = kToesShareOfFoot * kFoot.mass * M_;
    const Vector3 c(0, -h_ankle_ + 0.5 * toes_size().y(), p_FootMtp().z() + 0.5 * toes_length());
    return {m, c, box_inertia(m, toes_size())};
  }

  LinkSpec foot() const {
    LinkSpec l = link("l_foot", "l_shank", "Left foot", "l_ankle", JointType::kSpherical,
                      Vector3(0, -L_shank_, 0), kWeightWristAnkle);
    set_body(l, remainder(whole_foot(), {toes_in_foot()}));
    // nominal direction along the foot (+z); ψ = 0 plantar flexion (toes down), 90° abduction
    // (toe-out, lateral), 180° dorsiflexion, 270° adduction (toe-in); twist about the foot's
    // long axis, positive = eversion. AAOS (1965): plantar flexion 50°, inversion 35°, eversion
    // 15°, forefoot adduction 20°, abduction 10°. Dorsiflexion: AAOS gives 20° for the unloaded
    // foot, but with the body's weight on it (knee over the toes, as in a squat or a lunge) it
    // reaches 35–45° (weight-bearing lunge test, Bennell et al. 1998); a posing figure squats
    // with its feet pinned flat, so it gets the weight-bearing 35°.
    const Quaternion F = range_frame(Vector3::UnitZ(), -Vector3::UnitY());
    l.joint.range = elliptic_range(F, deg(50), deg(10), deg(35), deg(20), deg(-35), deg(15));
    const double zh = z_heel();
    const double zm = p_FootMtp().z();
    const double hb = kFootBoxHeight * h_ankle_;
    set_geometry(l, {box(Vector3(0, -h_ankle_ + 0.5 * hb, 0.5 * (zh + zm)),
                         Vector3(kFootWidth * H_, hb, zm - zh))});
    return l;
  }

  LinkSpec toes() const {
    // metatarsophalangeal joint, flexion (toes down) positive about +x
    LinkSpec l = link("l_toes", "l_foot", "Left toes", "l_toe", only48(JointType::kRevolute),
                      p_FootMtp(), kWeightToes);
    l.joint.axis = Vector3::UnitX();
    // AAOS (1965), first MTP: flexion 45°, extension 70°
    if (full_) l.joint.limits = {deg(-70), deg(45)};
    Body b = toes_in_foot();
    b.com -= p_FootMtp();
    set_body(l, b);
    set_geometry(l, {box(b.com, toes_size())});
    return l;
  }

  double H_, M_, s_;
  bool full_;
  double h_ankle_, L_shank_, L_thigh_, L_pelvis_, L_abdomen_, L_chest_, L_column_, L_neck_, L_head_,
      L_uarm_, L_farm_, L_hand_, L_foot_;
};

}  // namespace

std::shared_ptr<const Model> build_human_figure(const HumanFigureOptions& options) {
  if (!std::isfinite(options.height) || options.height < kHumanMinHeight ||
      options.height > kHumanMaxHeight) {
    throw std::invalid_argument("human figure: height " + std::to_string(options.height) +
                                " m is outside [" + std::to_string(kHumanMinHeight) + ", " +
                                std::to_string(kHumanMaxHeight) + "] m");
  }
  if (!std::isfinite(options.mass) || options.mass < kHumanMinMass ||
      options.mass > kHumanMaxMass) {
    throw std::invalid_argument("human figure: mass " + std::to_string(options.mass) +
                                " kg is outside [" + std::to_string(kHumanMinMass) + ", " +
                                std::to_string(kHumanMaxMass) + "] kg");
  }
  if (options.dof != 34 && options.dof != 48) {
    throw std::invalid_argument("human figure: dof " + std::to_string(options.dof) +
                                " is not supported (rule: 34 or 48)");
  }
  return FigureBuilder(options).build();
}

}  // namespace core
