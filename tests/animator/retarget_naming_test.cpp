// Naming conventions beyond the capture files' own: the CMU walk with its joints renamed the way
// Maya HumanIK (its Character1_ prefix), Mixamo (its namespace's colon lost), Unreal Engine,
// Blender/Rigify, VRoid, Daz, Character Creator and SMPL skeletons name them is
// recognised part for part and retargets onto human48 exactly as the original does
// (animator/joint_names.hpp).
#include <gtest/gtest.h>

#include <array>
#include <map>
#include <sstream>

#include "animator/joint_names.hpp"
#include "animator/retarget.hpp"
#include "core/human_figure.hpp"
#include "io/bvh.hpp"
#include "io/read_file.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using animator::kBodyPartCount;

struct Naming {
  const char* convention;
  std::array<const char*, kBodyPartCount> names;  // BodyPart order, as a file spells them
};

// clang-format off
const Naming kNamings[] = {
    // Maya's HumanIK skeleton with its default character prefix
    {"humanik",
     {"Character1_Hips", "Character1_Spine", "Character1_Spine2", "Character1_Neck",
      "Character1_Head", "Character1_LeftShoulder", "Character1_LeftArm",
      "Character1_LeftForeArm", "Character1_LeftHand", "Character1_RightShoulder",
      "Character1_RightArm", "Character1_RightForeArm", "Character1_RightHand",
      "Character1_LeftUpLeg", "Character1_LeftLeg", "Character1_LeftFoot", "Character1_LeftToeBase",
      "Character1_RightUpLeg", "Character1_RightLeg", "Character1_RightFoot",
      "Character1_RightToeBase"}},
    // Mixamo's rig after a tool dropped the namespace's ':' (three.js sanitizes node names so)
    {"mixamo",
     {"mixamorigHips", "mixamorigSpine", "mixamorigSpine2", "mixamorigNeck", "mixamorigHead",
      "mixamorigLeftShoulder", "mixamorigLeftArm", "mixamorigLeftForeArm", "mixamorigLeftHand",
      "mixamorigRightShoulder", "mixamorigRightArm", "mixamorigRightForeArm", "mixamorigRightHand",
      "mixamorigLeftUpLeg", "mixamorigLeftLeg", "mixamorigLeftFoot", "mixamorigLeftToeBase",
      "mixamorigRightUpLeg", "mixamorigRightLeg", "mixamorigRightFoot", "mixamorigRightToeBase"}},
    {"unreal",
     {"pelvis", "spine_01", "spine_03", "neck_01", "head",
      "clavicle_l", "upperarm_l", "lowerarm_l", "hand_l",
      "clavicle_r", "upperarm_r", "lowerarm_r", "hand_r",
      "thigh_l", "calf_l", "foot_l", "ball_l", "thigh_r", "calf_r", "foot_r", "ball_r"}},
    {"rigify",
     {"DEF-spine", "DEF-spine.001", "DEF-spine.003", "DEF-spine.004", "DEF-spine.006",
      "DEF-shoulder.L", "DEF-upper_arm.L", "DEF-forearm.L", "DEF-hand.L",
      "DEF-shoulder.R", "DEF-upper_arm.R", "DEF-forearm.R", "DEF-hand.R",
      "DEF-thigh.L", "DEF-shin.L", "DEF-foot.L", "DEF-toe.L",
      "DEF-thigh.R", "DEF-shin.R", "DEF-foot.R", "DEF-toe.R"}},
    {"vrm",
     {"J_Bip_C_Hips", "J_Bip_C_Spine", "J_Bip_C_UpperChest", "J_Bip_C_Neck", "J_Bip_C_Head",
      "J_Bip_L_Shoulder", "J_Bip_L_UpperArm", "J_Bip_L_LowerArm", "J_Bip_L_Hand",
      "J_Bip_R_Shoulder", "J_Bip_R_UpperArm", "J_Bip_R_LowerArm", "J_Bip_R_Hand",
      "J_Bip_L_UpperLeg", "J_Bip_L_LowerLeg", "J_Bip_L_Foot", "J_Bip_L_ToeBase",
      "J_Bip_R_UpperLeg", "J_Bip_R_LowerLeg", "J_Bip_R_Foot", "J_Bip_R_ToeBase"}},
    {"daz",
     {"hip", "abdomenLower", "chestUpper", "neckLower", "head",
      "lCollar", "lShldrBend", "lForearmBend", "lHand",
      "rCollar", "rShldrBend", "rForearmBend", "rHand",
      "lThighBend", "lShin", "lFoot", "lToe", "rThighBend", "rShin", "rFoot", "rToe"}},
    {"charactercreator",
     {"CC_Base_Hip", "CC_Base_Waist", "CC_Base_Spine02", "CC_Base_NeckTwist01", "CC_Base_Head",
      "CC_Base_L_Clavicle", "CC_Base_L_Upperarm", "CC_Base_L_Forearm", "CC_Base_L_Hand",
      "CC_Base_R_Clavicle", "CC_Base_R_Upperarm", "CC_Base_R_Forearm", "CC_Base_R_Hand",
      "CC_Base_L_Thigh", "CC_Base_L_Calf", "CC_Base_L_Foot", "CC_Base_L_ToeBase",
      "CC_Base_R_Thigh", "CC_Base_R_Calf", "CC_Base_R_Foot", "CC_Base_R_ToeBase"}},
    {"smpl",
     {"pelvis", "spine1", "spine3", "neck", "head",
      "left_collar", "left_shoulder", "left_elbow", "left_wrist",
      "right_collar", "right_shoulder", "right_elbow", "right_wrist",
      "left_hip", "left_knee", "left_ankle", "left_foot",
      "right_hip", "right_knee", "right_ankle", "right_foot"}},
};
// clang-format on

void PrintTo(const Naming& naming, std::ostream* os) { *os << naming.convention; }

// The BVH text with every ROOT and JOINT renamed: body parts by `renamed`, the others
// "extra_<n>" so no leftover name means a part in the new convention.
std::string rename_joints(const std::string& text,
                          const std::map<std::string, std::string>& renamed) {
  std::istringstream in(text);
  std::string out, line;
  int extra = 0;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string keyword, name;
    words >> keyword >> name;
    if (keyword == "ROOT" || keyword == "JOINT") {
      const auto it = renamed.find(name);
      const std::string new_name =
          it != renamed.end() ? it->second : "extra_" + std::to_string(extra++);
      line = line.substr(0, line.find(keyword)) + keyword + " " + new_name;
    }
    out += line + "\n";
  }
  return out;
}

class RetargetNaming : public ::testing::TestWithParam<Naming> {};

TEST_P(RetargetNaming, RenamedWalkMapsPartForPartAndRetargetsTheSame) {
  PINDRAG_REQUIRE_DATA_DIR();
  const Naming& naming = GetParam();
  const std::string path = fixtures::data_dir() + "/bvh/cmu_walk_cgspeed.bvh";
  const std::string text = io::read_file(path, io::kMaxBvhBytes);
  const io::BvhImport original = io::load_bvh_string(text, path);
  const animator::BodyPartGuess parts = animator::guess_body_parts(*original.model);
  ASSERT_EQ(parts.convention, "cmu");
  ASSERT_EQ(parts.recognised, kBodyPartCount);
  std::map<std::string, std::string> renamed;
  for (int p = 0; p < kBodyPartCount; ++p) {
    renamed[original.model->link_name[parts.link[p]]] = naming.names[p];
  }
  const io::BvhImport copy = io::load_bvh_string(rename_joints(text, renamed), "renamed.bvh");
  ASSERT_EQ(copy.model->njoints, original.model->njoints);

  const animator::BodyPartGuess copy_parts = animator::guess_body_parts(*copy.model);
  EXPECT_EQ(copy_parts.convention, naming.convention);
  EXPECT_EQ(copy_parts.recognised, kBodyPartCount);
  for (int p = 0; p < kBodyPartCount; ++p) {
    EXPECT_EQ(copy_parts.link[p], parts.link[p])
        << animator::to_string(static_cast<animator::BodyPart>(p)) << " is "
        << (copy_parts.link[p] < 0 ? "missing" : copy.model->link_name[copy_parts.link[p]]);
  }

  // the first second of the walk, retargeted from both: the same frames
  core::Clip clip = original.clip;
  clip.frames.resize(std::min<std::size_t>(clip.frames.size(), 120));
  core::Clip copy_clip = copy.clip;
  copy_clip.frames.resize(clip.frames.size());
  ASSERT_TRUE(copy_clip == clip);
  const auto human48 = core::build_human_figure({});
  const animator::RetargetResult a = animator::retarget(*original.model, clip, *human48);
  const animator::RetargetResult b = animator::retarget(*copy.model, copy_clip, *human48);
  EXPECT_EQ(b.report.source_convention, naming.convention);
  EXPECT_EQ(b.report.mapping, a.report.mapping);
  EXPECT_TRUE(b.clip == a.clip) << "the renamed skeleton retargets differently";
}

INSTANTIATE_TEST_SUITE_P(Conventions,
                         RetargetNaming,
                         ::testing::ValuesIn(kNamings),
                         [](const auto& naming) { return std::string(naming.param.convention); });

}  // namespace
