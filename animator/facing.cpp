#include "animator/facing.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>

#include "animator/joint_names.hpp"
#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "core/model_edit.hpp"

namespace animator {

namespace {

bool is_upper(char c) { return std::isupper(static_cast<unsigned char>(c)) != 0; }
bool is_lower(char c) { return std::islower(static_cast<unsigned char>(c)) != 0; }
bool is_digit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }
bool is_word_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0; }

// where a new word starts inside a run of letters and digits: lower → Upper ("leftArm"), the last
// capital of an acronym before lower case ("LHip"), and letters ↔ digits ("Leg01")
bool word_starts_at(const std::string& s, std::size_t i) {
  const char a = s[i - 1], b = s[i];
  if (is_lower(a) && is_upper(b)) return true;
  if (is_upper(a) && is_upper(b) && i + 1 < s.size() && is_lower(s[i + 1])) return true;
  return is_digit(a) != is_digit(b);
}

// `word` → its opposite side in the same letter case ("L" → "R", "Left" → "Right", "left" →
// "right", "LEFT" → "RIGHT")
std::string opposite_in_case(const std::string& word, const std::string& opposite) {
  std::string out = opposite;
  const bool all_upper = is_upper(word[0]) && (word.size() == 1 || is_upper(word[1]));
  for (std::size_t k = 0; k < out.size(); ++k) {
    const bool upper = all_upper || (k == 0 && is_upper(word[0]));
    out[k] = static_cast<char>(upper ? std::toupper(static_cast<unsigned char>(out[k])) : out[k]);
  }
  return out;
}

// A four-legged robot's leg code: fore/hind and side in either order ("FL", "RR" as front-left,
// rear-right; "LF", "RH" as left-fore, right-hind). The index of the side letter in `word`, or
// -1 when it is not such a code.
int leg_code_side(const std::string& word) {
  if (word.size() != 2) return -1;
  const std::string w = normalize_joint_name(word);  // a word: letters and digits, lower-cased
  const auto is_side = [](char c) { return c == 'l' || c == 'r'; };
  if (is_side(w[0]) && (w[1] == 'f' || w[1] == 'h')) return 0;
  if ((w[0] == 'f' || w[0] == 'h' || w[0] == 'r') && is_side(w[1])) return 1;
  return -1;
}

bool is_ancestor(const core::Model& model, int ancestor, int link) {
  for (int k = model.parent[link]; k > 0; k = model.parent[k]) {
    if (k == ancestor) return true;
  }
  return false;
}

}  // namespace

std::optional<std::pair<std::string, bool>> mirrored_name(const std::string& name) {
  std::size_t i = 0;
  while (i < name.size()) {
    if (!is_word_char(name[i])) {
      ++i;
      continue;
    }
    std::size_t end = i + 1;
    while (end < name.size() && is_word_char(name[end]) && !word_starts_at(name, end)) ++end;
    const std::string word = name.substr(i, end - i);
    const std::string side = normalize_joint_name(word);  // the word in lower case
    if (side == "l" || side == "left" || side == "r" || side == "right") {
      const bool left = side[0] == 'l';
      const std::string opposite =
          side.size() == 1 ? (left ? "r" : "l") : (left ? "right" : "left");
      return std::make_pair(name.substr(0, i) + opposite_in_case(word, opposite) + name.substr(end),
                            left);
    }
    if (const int k = leg_code_side(word); k >= 0) {
      const bool left = side[k] == 'l';
      std::string swapped = word;
      swapped[k] = opposite_in_case(word.substr(k, 1), left ? "r" : "l")[0];
      return std::make_pair(name.substr(0, i) + swapped + name.substr(end), left);
    }
    i = end;
  }
  return std::nullopt;
}

std::vector<std::pair<int, int>> left_right_pairs(const core::Model& model) {
  std::vector<std::pair<int, int>> pairs;
  // a humanoid convention: the hips (thighs' origins) and the shoulders (upper arms' origins)
  const BodyPartGuess parts = guess_body_parts(model);
  const auto add_part_pair = [&](BodyPart left, BodyPart right) {
    const int l = parts.link[static_cast<int>(left)], r = parts.link[static_cast<int>(right)];
    if (l >= 0 && r >= 0 && l != r) pairs.emplace_back(l, r);
  };
  add_part_pair(BodyPart::kLeftThigh, BodyPart::kRightThigh);
  add_part_pair(BodyPart::kLeftUpperArm, BodyPart::kRightUpperArm);
  if (!pairs.empty()) return pairs;

  // else side words: every left link whose mirrored name is a link, then only the first pair of
  // each limb (no left link of another pair above it)
  std::vector<std::pair<int, int>> named;
  for (int i = 1; i < model.njoints; ++i) {
    const auto mirrored = mirrored_name(model.link_name[i]);
    if (!mirrored || !mirrored->second) continue;
    const int j = model.link_index(mirrored->first);
    if (j > 0 && j != i) named.emplace_back(i, j);
  }
  for (const auto& [l, r] : named) {
    bool first_of_limb = true;
    for (const auto& other : named)
      first_of_limb = first_of_limb && !is_ancestor(model, other.first, l);
    if (first_of_limb) pairs.emplace_back(l, r);
  }
  return pairs;
}

std::optional<core::Vector3> facing_from_sides(const core::Data& data,
                                               const std::vector<std::pair<int, int>>& pairs) {
  core::Vector3 left = core::Vector3::Zero();
  for (const auto& [l, r] : pairs) left += data.X_W[l].p - data.X_W[r].p;
  const core::Vector3 horizontal(left.x(), 0.0, left.z());
  // more than 30° from vertical: horizontal part at least sin 30° of the whole
  if (!(left.norm() > 0) || !(horizontal.norm() >= 0.5 * left.norm())) return std::nullopt;
  // left × up with up = +Y
  return core::Vector3(-horizontal.z(), 0.0, horizontal.x()).normalized();
}

std::vector<std::pair<int, int>> toe_links(const core::Model& model) {
  std::vector<std::pair<int, int>> toes;
  if (model.njoints < 3) return toes;
  core::Data data(model);
  core::forward_kinematics(model, data, core::rest_configuration(model));
  double low = core::kInfinity, high = -core::kInfinity;
  for (int i = 1; i < model.njoints; ++i) {
    low = std::min(low, data.X_W[i].p.y());
    high = std::max(high, data.X_W[i].p.y());
  }
  const double root_height = data.X_W[1].p.y();
  core::Vector3 sum = core::Vector3::Zero();
  std::vector<core::Vector3> horizontals;
  for (int i = 2; i < model.njoints; ++i) {
    const int parent = model.parent[i];
    const double y = data.X_W[i].p.y();
    const bool leaf = model.subtree_end[i] == i + 1;
    if (!leaf || parent <= 1 || y > low + 0.15 * (high - low) || !(y < root_height)) continue;
    const core::Vector3 bone = data.X_W[i].p - data.X_W[parent].p;
    const core::Vector3 horizontal(bone.x(), 0.0, bone.z());
    // at least 15° from vertical: sin 15° of the bone horizontal
    if (!(horizontal.norm() >= std::sin(15 * std::numbers::pi / 180) * bone.norm())) continue;
    toes.emplace_back(parent, i);
    horizontals.push_back(horizontal);
    sum += horizontal;
  }
  for (const core::Vector3& h : horizontals) {
    if (!(h.dot(sum) > 0)) return {};
  }
  return toes;
}

std::optional<core::Vector3> facing_from_toes(const core::Model& model,
                                              const core::Data& data,
                                              const std::vector<std::pair<int, int>>& toes) {
  if (toes.empty()) return std::nullopt;
  // where the toes point in the rest pose, in the root link's frame, then in this pose
  core::Data rest(model);
  core::forward_kinematics(model, rest, core::rest_configuration(model));
  core::Vector3 sum = core::Vector3::Zero();
  for (const auto& [parent, leaf] : toes) sum += rest.X_W[leaf].p - rest.X_W[parent].p;
  sum.y() = 0;
  const core::Vector3 now = data.X_W[1].R * (rest.X_W[1].R.transpose() * sum);
  const core::Vector3 horizontal(now.x(), 0.0, now.z());
  if (!(horizontal.norm() >= 0.5 * now.norm())) return std::nullopt;
  return horizontal.normalized();
}

std::optional<Facing> facing_of(const core::Model& model, const core::Data& data) {
  if (model.njoints < 2) return std::nullopt;
  Facing out;
  out.links = left_right_pairs(model);
  if (!out.links.empty()) {
    const auto direction = facing_from_sides(data, out.links);
    if (!direction) return std::nullopt;
    out.direction = *direction;
    return out;
  }
  out.links = toe_links(model);
  const auto direction = facing_from_toes(model, data, out.links);
  if (!direction) return std::nullopt;
  out.direction = *direction;
  out.by_toes = true;
  return out;
}

std::optional<core::Vector3> rest_up(const core::Model& model) {
  const BodyPartGuess parts = guess_body_parts(model);
  const auto link = [&](BodyPart p) { return parts.link[static_cast<int>(p)]; };
  const int hips = link(BodyPart::kHips);
  const int left_foot = link(BodyPart::kLeftFoot), right_foot = link(BodyPart::kRightFoot);
  if (hips < 0 || left_foot < 0 || right_foot < 0) return std::nullopt;
  core::Data rest(model);
  core::forward_kinematics(model, rest, core::rest_configuration(model));
  const core::Vector3 feet = 0.5 * (rest.X_W[left_foot].p + rest.X_W[right_foot].p);
  const core::Vector3 standing = rest.X_W[hips].p - feet;  // from the feet up to the hips
  for (BodyPart top : {BodyPart::kHead, BodyPart::kNeck, BodyPart::kChest}) {
    const int t = link(top);
    if (t < 0 || t == hips) continue;
    const core::Vector3 spine = rest.X_W[t].p - rest.X_W[hips].p;  // from the hips up
    if (!(spine.norm() > 0) || !(standing.norm() > 0)) return std::nullopt;
    // a biped's legs and spine make one line; a four-legged figure's spine is level over its legs
    const core::Vector3 a = spine.normalized(), b = standing.normalized();
    if (!(a.dot(b) >= std::sqrt(0.5))) return std::nullopt;
    return (a + b).normalized();
  }
  return std::nullopt;
}

std::shared_ptr<const core::Model> stand_upright(const std::shared_ptr<const core::Model>& model) {
  if (model->njoints < 2) return model;
  const auto up = rest_up(*model);
  const double cos45 = std::sqrt(0.5);
  if (!up || up->y() >= cos45) return model;
  // the axis it is within 45° of, and the quarter or half turn taking that axis to +Y
  int axis = 0;
  up->cwiseAbs().maxCoeff(&axis);
  if (std::abs((*up)[axis]) < cos45) return model;
  const double sign = (*up)[axis] > 0 ? 1.0 : -1.0;
  const double quarter = std::numbers::pi / 2;
  core::Matrix3 R;
  if (axis == 2) {  // ±Z → +Y: about X by ∓90°
    R = Eigen::AngleAxisd(-sign * quarter, core::Vector3::UnitX()).toRotationMatrix();
  } else if (axis == 0) {  // ±X → +Y: about Z by ±90°
    R = Eigen::AngleAxisd(sign * quarter, core::Vector3::UnitZ()).toRotationMatrix();
  } else {  // −Y → +Y: a half turn about X
    R = Eigen::AngleAxisd(2 * quarter, core::Vector3::UnitX()).toRotationMatrix();
  }
  core::Data rest(*model);
  core::forward_kinematics(*model, rest, core::rest_configuration(*model));
  return core::turn_root(*model, R, rest.X_W[1].p);
}

Faced face_forward(const std::shared_ptr<const core::Model>& model, const Eigen::VectorXd& q) {
  Faced out{model, 0.0, false};
  core::Data data(*model);
  core::forward_kinematics(*model, data, q);
  const auto facing = facing_of(*model, data);
  if (!facing) return out;
  out.known = true;
  // facing (sin φ, 0, cos φ) turns onto +Z by −φ about +Y
  const double turn = -std::atan2(facing->direction.x(), facing->direction.z());
  if (std::abs(turn) <= 1e-9) return out;
  const core::Matrix3 about_vertical =
      Eigen::AngleAxisd(turn, core::Vector3::UnitY()).toRotationMatrix();
  out.model = core::turn_root(*model, about_vertical, data.X_W[1].p);
  out.turn = turn;
  return out;
}

}  // namespace animator
