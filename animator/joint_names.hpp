// Joint naming conventions of humanoid skeletons and the correspondence between two skeletons
// guessed from their names, for retargeting clips (animator/retarget.hpp).
//
// Each convention lists, for every body part, the names a skeleton of that convention gives it,
// in order of preference. Names are compared normalized: the part before the last ':' dropped
// ("mixamorig:LeftArm", "Male:LFWT"), a leading "Bip01"/"Bip001", "mixamorig" (its ':' lost:
// "mixamorig_Hips") or "Character1" (Maya HumanIK's default prefix) dropped, letters lowercased
// and everything but letters and digits removed, so "Bip01 L UpperArm" reads "lupperarm". A
// skeleton gets the convention that recognises the most of its joints: the same name can mean
// different parts in two conventions ("LeftShoulder" is the clavicle in CMU's MotionBuilder release
// and Mixamo, the upper arm in CMU's 3ds Max release and Biovision files).
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/model.hpp"

namespace animator {

/// The body parts retargeting knows by name.
enum class BodyPart {
  kHips,
  kSpine,
  kChest,
  kNeck,
  kHead,
  kLeftClavicle,
  kLeftUpperArm,
  kLeftForearm,
  kLeftHand,
  kRightClavicle,
  kRightUpperArm,
  kRightForearm,
  kRightHand,
  kLeftThigh,
  kLeftShin,
  kLeftFoot,
  kLeftToes,
  kRightThigh,
  kRightShin,
  kRightFoot,
  kRightToes,
};
constexpr int kBodyPartCount = 21;
/// "hips", "spine", ..., "l_upper_arm", ..., "r_toes"
const char* to_string(BodyPart p);

/// Per body part, a link index of some model, or -1.
using BodyPartLinks = std::array<int, kBodyPartCount>;

/// The name as conventions compare it (see the file comment).
std::string normalize_joint_name(std::string_view name);

/// The body parts of a model by the convention that recognises most of its links.
struct BodyPartGuess {
  std::string convention;  // "cmu", "mixamo", ...; empty when no part was recognised
  BodyPartLinks link{};    // -1 where the part was not found
  int recognised = 0;
};
BodyPartGuess guess_body_parts(const core::Model& model);

/// Which source link drives which target link (a bijection between the mapped links).
struct Correspondence {
  std::vector<int> target_of_source;  // per source link (njoints), -1 when unmapped
  std::vector<int> source_of_target;  // per target link (njoints), -1 when unmapped
  BodyPartGuess source_parts, target_parts;
  /// The target link of a body part: as the target's names say, else the link its source part
  /// is mapped to; -1 when neither.
  int target_of(BodyPart p) const {
    const int t = target_parts.link[static_cast<int>(p)];
    if (t >= 0) return t;
    const int s = source_parts.link[static_cast<int>(p)];
    return s < 0 ? -1 : target_of_source[s];
  }
  /// The source link that drives the target link of a body part, or -1.
  int source_of(BodyPart p) const {
    const int t = target_of(p);
    return t < 0 ? -1 : source_of_target[t];
  }
};

/// Pairs the links of the two models that play the same body part.
Correspondence guess_correspondence(const core::Model& source, const core::Model& target);

/// One entry of a user's mapping: source joint name → target link name, or no target to leave
/// the source joint unmapped.
struct MappingEntry {
  std::string source;
  std::optional<std::string> target;
};

/// A mapping document {"source joint": "target link" or null, ...} as entries, by joint name.
/// @throws std::invalid_argument "<origin>: /<joint>: <rule>" for a value that is neither a
///         string nor null, or "<origin>: / : ..." when the document is not an object
std::vector<MappingEntry> mapping_from_json(const nlohmann::json& doc, const std::string& origin);

/// Applies the user's entries over the guesses: an entry replaces whatever its source joint and
/// its target link were paired with. `origin` names where the entries come from.
/// @throws std::invalid_argument naming origin, the entry and the rule (a joint the clip does
///         not have, a link the character does not have, a link given twice)
void apply_mapping(const core::Model& source,
                   const core::Model& target,
                   const std::vector<MappingEntry>& entries,
                   const std::string& origin,
                   Correspondence& c);

}  // namespace animator
