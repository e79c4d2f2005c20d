#include "animator/joint_names.hpp"

#include <cctype>
#include <set>
#include <stdexcept>

namespace animator {

namespace {

// one convention: per body part (BodyPart order) the normalized names it uses, preferred first
// ("a|b" lists alternatives); `prefix` limits it to skeletons whose raw names start with it
struct Convention {
  const char* name;
  const char* prefix;
  std::array<const char*, kBodyPartCount> parts;
};

// clang-format off
const Convention kConventions[] = {
    // the bundled figures (core/human_figure.hpp)
    {"pindrag", "",
     {"pelvis", "abdomen", "chest", "neck", "head",
      "lclav", "luarm", "lfarm", "lhand", "rclav", "ruarm", "rfarm", "rhand",
      "lthigh", "lshank", "lfoot", "ltoes", "rthigh", "rshank", "rfoot", "rtoes"}},
    // Mixamo: the HumanIK names behind a "mixamorig:" namespace
    {"mixamo", "mixamorig",
     {"hips", "spine", "spine2|spine1", "neck", "head",
      "leftshoulder", "leftarm", "leftforearm", "lefthand",
      "rightshoulder", "rightarm", "rightforearm", "righthand",
      "leftupleg", "leftleg", "leftfoot", "lefttoebase",
      "rightupleg", "rightleg", "rightfoot", "righttoebase"}},
    // CMU in the MotionBuilder-friendly release: LowerBack, Spine, Spine1, Neck, Neck1, Head
    {"cmu", "",
     {"hips", "lowerback", "spine", "neck", "head",
      "leftshoulder", "leftarm", "leftforearm", "lefthand",
      "rightshoulder", "rightarm", "rightforearm", "righthand",
      "leftupleg", "leftleg", "leftfoot", "lefttoebase",
      "rightupleg", "rightleg", "rightfoot", "righttoebase"}},
    // MotionBuilder HumanIK: Spine, Spine1...SpineN, Neck, Head
    {"humanik", "",
     {"hips", "spine", "spine2|spine1", "neck|neck1", "head",
      "leftshoulder", "leftarm", "leftforearm", "lefthand",
      "rightshoulder", "rightarm", "rightforearm", "righthand",
      "leftupleg", "leftleg", "leftfoot", "lefttoebase",
      "rightupleg", "rightleg", "rightfoot", "righttoebase"}},
    // Biovision files and CMU's 3ds Max-friendly release: Collar, Shoulder, Elbow, Wrist
    {"biovision", "",
     {"hips", "lowerback|ab|abdomen", "chest|chest2", "neck|lowerneck", "head",
      "leftcollar", "leftshoulder|leftuparm", "leftelbow|leftlowarm", "leftwrist|lefthand",
      "rightcollar", "rightshoulder|rightuparm", "rightelbow|rightlowarm", "rightwrist|righthand",
      "lefthip|leftupleg", "leftknee|leftlowleg", "leftankle|leftfoot", "lefttoe|lefttoes",
      "righthip|rightupleg", "rightknee|rightlowleg", "rightankle|rightfoot",
      "righttoe|righttoes"}},
    // 3ds Max Biped ("Bip01 L UpperArm"; the "Bip01" is dropped when names are normalized)
    {"biped", "",
     {"pelvis", "spine", "spine2|spine1", "neck", "head",
      "lclavicle", "lupperarm", "lforearm", "lhand",
      "rclavicle", "rupperarm", "rforearm", "rhand",
      "lthigh", "lcalf", "lfoot", "ltoe0|ltoe",
      "rthigh", "rcalf", "rfoot", "rtoe0|rtoe"}},
    // Vicon Plug-in Gait segments, by name or by their three-letter codes
    {"plugingait", "",
     {"pelvis|pel", "", "thorax|trx", "", "head|hed",
      "lclavicle|lcl", "lhumerus|lhu", "lradius|lra", "lhand|lhn",
      "rclavicle|rcl", "rhumerus|rhu", "rradius|rra", "rhand|rhn",
      "lfemur|lfe", "ltibia|lti", "lfoot|lfo", "ltoes|ltoe|lto",
      "rfemur|rfe", "rtibia|rti", "rfoot|rfo", "rtoes|rtoe|rto"}},
    // Unreal Engine's mannequins: spine_01 ... spine_03 (UE4) or spine_05 (UE5), the clavicles
    // hanging from the last
    {"unreal", "",
     {"pelvis", "spine01", "spine05|spine03|spine02", "neck01", "head",
      "claviclel", "upperarml", "lowerarml", "handl",
      "clavicler", "upperarmr", "lowerarmr", "handr",
      "thighl", "calfl", "footl", "balll",
      "thighr", "calfr", "footr", "ballr"}},
    // Blender's human metarig and the deform bones Rigify generates from it ("DEF-thigh.L"):
    // "spine" is the hips, spine.003 carries the shoulders, spine.006 is the head. Blender's
    // older metarig named them hips, spine, chest, neck and head.
    {"rigify", "",
     {"hips|spine|defspine", "spine001|defspine001|spine", "spine003|defspine003|chest",
      "spine004|defspine004|neck", "spine006|defspine006|head",
      "shoulderl|defshoulderl", "upperarml|defupperarml", "forearml|defforearml", "handl|defhandl",
      "shoulderr|defshoulderr", "upperarmr|defupperarmr", "forearmr|defforearmr", "handr|defhandr",
      "thighl|defthighl", "shinl|defshinl", "footl|deffootl", "toel|deftoel",
      "thighr|defthighr", "shinr|defshinr", "footr|deffootr", "toer|deftoer"}},
    // Unity's and VRM's humanoid bones, by their names or VRoid's ("J_Bip_L_UpperArm");
    // LeftShoulder is the clavicle, as in Mixamo
    {"vrm", "",
     {"hips|jbipchips", "spine|jbipcspine", "upperchest|chest|jbipcupperchest|jbipcchest",
      "neck|jbipcneck", "head|jbipchead",
      "leftshoulder|jbiplshoulder", "leftupperarm|jbiplupperarm", "leftlowerarm|jbipllowerarm",
      "lefthand|jbiplhand",
      "rightshoulder|jbiprshoulder", "rightupperarm|jbiprupperarm", "rightlowerarm|jbiprlowerarm",
      "righthand|jbiprhand",
      "leftupperleg|jbiplupperleg", "leftlowerleg|jbipllowerleg", "leftfoot|jbiplfoot",
      "lefttoes|jbipltoebase",
      "rightupperleg|jbiprupperleg", "rightlowerleg|jbiprlowerleg", "rightfoot|jbiprfoot",
      "righttoes|jbiprtoebase"}},
    // Daz Genesis: 3 and 8 split limbs into Bend and Twist links (the Bend one plays the part),
    // 1 and 2 do not; "hip" is the root and "pelvis" below it only carries the thighs
    {"daz", "",
     {"hip", "abdomenlower|abdomen", "chestupper|chestlower|chest", "necklower|neck", "head",
      "lcollar", "lshldrbend|lshldr", "lforearmbend|lforearm", "lhand",
      "rcollar", "rshldrbend|rshldr", "rforearmbend|rforearm", "rhand",
      "lthighbend|lthigh", "lshin", "lfoot", "ltoe",
      "rthighbend|rthigh", "rshin", "rfoot", "rtoe"}},
    // Reallusion Character Creator ("CC_Base_L_Thigh"): Hip above Pelvis (the thighs) and Waist
    // (the spine), the clavicles on Spine02
    {"charactercreator", "",
     {"ccbasehip", "ccbasewaist", "ccbasespine02|ccbasespine01", "ccbasenecktwist01|ccbaseneck",
      "ccbasehead",
      "ccbaselclavicle", "ccbaselupperarm", "ccbaselforearm", "ccbaselhand",
      "ccbaserclavicle", "ccbaserupperarm", "ccbaserforearm", "ccbaserhand",
      "ccbaselthigh", "ccbaselcalf", "ccbaselfoot", "ccbaseltoebase",
      "ccbaserthigh", "ccbasercalf", "ccbaserfoot", "ccbasertoebase"}},
    // SMPL's joints (body models and the captures fitted with them, AMASS), long or short
    // ("left_hip", "L_Hip"): the joint names where a part rotates, so the "ankle" is the foot,
    // the "foot" the toes, the "collar" the clavicle and the "shoulder" the upper arm
    {"smpl", "",
     {"pelvis", "spine1", "spine3|spine2", "neck", "head",
      "leftcollar|lcollar", "leftshoulder|lshoulder", "leftelbow|lelbow", "leftwrist|lwrist",
      "rightcollar|rcollar", "rightshoulder|rshoulder", "rightelbow|relbow", "rightwrist|rwrist",
      "lefthip|lhip", "leftknee|lknee", "leftankle|lankle", "leftfoot|lfoot",
      "righthip|rhip", "rightknee|rknee", "rightankle|rankle", "rightfoot|rfoot"}},
};

const char* const kPartNames[kBodyPartCount] = {
    "hips", "spine", "chest", "neck", "head",
    "l_clavicle", "l_upper_arm", "l_forearm", "l_hand",
    "r_clavicle", "r_upper_arm", "r_forearm", "r_hand",
    "l_thigh", "l_shin", "l_foot", "l_toes", "r_thigh", "r_shin", "r_foot", "r_toes"};
// clang-format on

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// the alternatives of "a|b|c"
std::vector<std::string> alternatives(const char* list) {
  std::vector<std::string> out;
  std::string_view s(list);
  while (!s.empty()) {
    const auto bar = s.find('|');
    out.emplace_back(s.substr(0, bar));
    if (bar == std::string_view::npos) break;
    s.remove_prefix(bar + 1);
  }
  return out;
}

BodyPartGuess apply_convention(const core::Model& model,
                               const Convention& c,
                               const std::vector<std::string>& normalized) {
  BodyPartGuess g;
  g.convention = c.name;
  g.link.fill(-1);
  std::set<int> used;
  for (int p = 0; p < kBodyPartCount; ++p) {
    for (const std::string& name : alternatives(c.parts[p])) {
      for (int i = 1; i < model.njoints && g.link[p] < 0; ++i) {
        if (normalized[i] != name || used.count(i)) continue;
        if (*c.prefix && lower(model.link_name[i]).rfind(c.prefix, 0) != 0) continue;
        g.link[p] = i;
        used.insert(i);
        ++g.recognised;
      }
      if (g.link[p] >= 0) break;
    }
  }
  return g;
}

}  // namespace

const char* to_string(BodyPart p) { return kPartNames[static_cast<int>(p)]; }

std::string normalize_joint_name(std::string_view name) {
  const auto colon = name.rfind(':');
  if (colon != std::string_view::npos) name.remove_prefix(colon + 1);
  std::string out;
  for (char c : name) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
  }
  for (const char* biped : {"bip001", "bip01"}) {
    const std::string b(biped);
    if (out.size() > b.size() && out.rfind(b, 0) == 0) return out.substr(b.size());
  }
  // a namespace whose ':' was lost ("mixamorig_Hips", or "mixamorigHips" from tools that drop
  // the character), and Maya HumanIK's default "Character1_" prefix: a word, optional digits
  for (const auto& [word, needs_digits] : {std::pair{"mixamorig", false}, {"character", true}}) {
    const std::string w(word);
    if (out.rfind(w, 0) != 0) continue;
    std::size_t end = w.size();
    while (end < out.size() && std::isdigit(static_cast<unsigned char>(out[end]))) ++end;
    if ((!needs_digits || end > w.size()) && end < out.size()) return out.substr(end);
  }
  return out;
}

BodyPartGuess guess_body_parts(const core::Model& model) {
  std::vector<std::string> normalized(model.njoints);
  for (int i = 1; i < model.njoints; ++i) normalized[i] = normalize_joint_name(model.link_name[i]);
  BodyPartGuess best;
  best.link.fill(-1);
  for (const Convention& c : kConventions) {
    BodyPartGuess g = apply_convention(model, c, normalized);
    if (g.recognised > best.recognised) best = g;  // ties: the convention listed first
  }
  return best;
}

Correspondence guess_correspondence(const core::Model& source, const core::Model& target) {
  Correspondence c;
  c.target_of_source.assign(source.njoints, -1);
  c.source_of_target.assign(target.njoints, -1);
  c.source_parts = guess_body_parts(source);
  c.target_parts = guess_body_parts(target);
  for (int p = 0; p < kBodyPartCount; ++p) {
    const int s = c.source_parts.link[p], t = c.target_parts.link[p];
    if (s < 0 || t < 0) continue;
    c.target_of_source[s] = t;
    c.source_of_target[t] = s;
  }
  return c;
}

std::vector<MappingEntry> mapping_from_json(const nlohmann::json& doc, const std::string& origin) {
  if (!doc.is_object()) {
    throw std::invalid_argument(origin + ": / : expected an object of source joint name -> " +
                                "target link name, got " + doc.type_name());
  }
  std::vector<MappingEntry> out;
  for (const auto& [key, value] : doc.items()) {
    if (value.is_null()) {
      out.push_back({key, std::nullopt});
    } else if (value.is_string()) {
      out.push_back({key, value.get<std::string>()});
    } else {
      throw std::invalid_argument(origin + ": /" + key +
                                  ": expected a link name (string) or null, got " +
                                  value.type_name());
    }
  }
  return out;
}

void apply_mapping(const core::Model& source,
                   const core::Model& target,
                   const std::vector<MappingEntry>& entries,
                   const std::string& origin,
                   Correspondence& c) {
  std::set<int> targets_given;
  for (const MappingEntry& e : entries) {
    const std::string field = origin + ": \"" + e.source + "\"";
    const int s = source.link_index(e.source);
    if (s <= 0) {
      throw std::invalid_argument(field +
                                  ": the clip has no joint of this name (rule: keys are joint "
                                  "names of the clip, spelled as in its file)");
    }
    int t = -1;
    if (e.target) {
      t = target.link_index(*e.target);
      if (t <= 0) {
        throw std::invalid_argument(field + ": the character has no link \"" + *e.target +
                                    "\" (rule: values are link names of the character, or null)");
      }
      if (!targets_given.insert(t).second) {
        throw std::invalid_argument(field + ": link \"" + *e.target +
                                    "\" is given twice (rule: each link is driven by one joint)");
      }
    }
    // unpair what the source joint and the target link were paired with
    if (c.target_of_source[s] >= 0) c.source_of_target[c.target_of_source[s]] = -1;
    c.target_of_source[s] = -1;
    if (t >= 0) {
      if (c.source_of_target[t] >= 0) c.target_of_source[c.source_of_target[t]] = -1;
      c.source_of_target[t] = s;
      c.target_of_source[s] = t;
    }
  }
}

}  // namespace animator
