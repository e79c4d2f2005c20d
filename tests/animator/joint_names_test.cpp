// Joint name conventions and the correspondence guessed from them (animator/joint_names.hpp).
#include "animator/joint_names.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

#include "core/human_figure.hpp"
#include "io/bvh.hpp"

namespace {

using animator::BodyPart;

// a BVH skeleton whose joints are the given names as one chain under the root (enough for names)
std::shared_ptr<const core::Model> named_skeleton(const std::vector<std::string>& names) {
  std::string text = "HIERARCHY\nROOT " + names[0] +
                     "\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation "
                     "Xrotation Yrotation\n";
  for (std::size_t i = 1; i < names.size(); ++i) {
    text += "JOINT " + names[i] + "\n{\nOFFSET 0 1 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n";
  }
  text += "End Site\n{\nOFFSET 0 1 0\n}\n";
  for (std::size_t i = 0; i < names.size(); ++i) text += "}\n";
  text += "MOTION\nFrames: 1\nFrame Time: 0.1\n";
  for (std::size_t i = 0; i < 3 * names.size() + 3; ++i) text += "0 ";
  text += "\n";
  return io::load_bvh_string(text, "test").model;
}

int part(const animator::BodyPartGuess& g, BodyPart p) { return g.link[static_cast<int>(p)]; }

TEST(JointNames, NormalizeDropsNamespacesPrefixesAndSeparators) {
  EXPECT_EQ(animator::normalize_joint_name("mixamorig:LeftArm"), "leftarm");
  EXPECT_EQ(animator::normalize_joint_name("Bip01 L UpperArm"), "lupperarm");
  EXPECT_EQ(animator::normalize_joint_name("Bip001 R Calf"), "rcalf");
  EXPECT_EQ(animator::normalize_joint_name("l_uarm"), "luarm");
  EXPECT_EQ(animator::normalize_joint_name("Bip01"), "bip01");
  EXPECT_EQ(animator::normalize_joint_name("mixamorig_Hips"), "hips");
  EXPECT_EQ(animator::normalize_joint_name("mixamorigLeftUpLeg"), "leftupleg");
  EXPECT_EQ(animator::normalize_joint_name("mixamorig1_Spine2"), "spine2");
  EXPECT_EQ(animator::normalize_joint_name("Character1_LeftUpLeg"), "leftupleg");
  EXPECT_EQ(animator::normalize_joint_name("Character1"), "character1");
  EXPECT_EQ(animator::normalize_joint_name("CharacterRoot"), "characterroot");
}

TEST(JointNames, LeftShoulderMeansWhatItsConventionSays) {
  // CMU's MotionBuilder release: LeftShoulder is the clavicle
  const auto mb = named_skeleton({"Hips", "LowerBack", "Spine", "LeftShoulder", "LeftArm",
                                  "LeftForeArm", "LeftHand", "LeftUpLeg", "LeftLeg"});
  const auto g1 = animator::guess_body_parts(*mb);
  EXPECT_EQ(g1.convention, "cmu");
  EXPECT_EQ(mb->link_name[part(g1, BodyPart::kLeftClavicle)], "LeftShoulder");
  EXPECT_EQ(mb->link_name[part(g1, BodyPart::kLeftUpperArm)], "LeftArm");
  // CMU's 3ds Max release and Biovision files: LeftShoulder is the upper arm
  const auto bv = named_skeleton({"Hips", "Chest", "LeftCollar", "LeftShoulder", "LeftElbow",
                                  "LeftWrist", "LeftHip", "LeftKnee", "LeftAnkle"});
  const auto g2 = animator::guess_body_parts(*bv);
  EXPECT_EQ(g2.convention, "biovision");
  EXPECT_EQ(bv->link_name[part(g2, BodyPart::kLeftClavicle)], "LeftCollar");
  EXPECT_EQ(bv->link_name[part(g2, BodyPart::kLeftUpperArm)], "LeftShoulder");
}

TEST(JointNames, BipedPlugInGaitMixamoAndTheBundledFigures) {
  const auto biped = named_skeleton({"Bip01", "Bip01_Pelvis", "Bip01_Spine", "Bip01_L_Thigh",
                                     "Bip01_L_Calf", "Bip01_L_Foot", "Bip01_L_UpperArm"});
  const auto gb = animator::guess_body_parts(*biped);
  EXPECT_EQ(gb.convention, "biped");
  EXPECT_EQ(biped->link_name[part(gb, BodyPart::kLeftShin)], "Bip01_L_Calf");
  const auto pig = named_skeleton({"Pelvis", "Thorax", "LFemur", "LTibia", "LFoot", "LHumerus"});
  const auto gp = animator::guess_body_parts(*pig);
  EXPECT_EQ(gp.convention, "plugingait");
  EXPECT_EQ(pig->link_name[part(gp, BodyPart::kLeftUpperArm)], "LHumerus");
  const auto mix = named_skeleton(
      {"mixamorig:Hips", "mixamorig:Spine", "mixamorig:LeftUpLeg", "mixamorig:LeftLeg"});
  EXPECT_EQ(animator::guess_body_parts(*mix).convention, "mixamo");
  for (int dof : {48, 34}) {
    core::HumanFigureOptions o;
    o.dof = dof;
    const auto fig = core::build_human_figure(o);
    const auto g = animator::guess_body_parts(*fig);
    EXPECT_EQ(g.convention, "pindrag");
    EXPECT_EQ(g.recognised, animator::kBodyPartCount) << dof;
  }
}

// Where these conventions part from the ones above: a name that means another part, or a part
// with several candidates
TEST(JointNames, UnrealRigifyVrmDazAndSmplNameTheirOwnParts) {
  // UE5's mannequin: five spine links, the clavicles on spine_05 (UE4's stop at spine_03)
  const auto ue5 =
      named_skeleton({"pelvis", "spine_01", "spine_02", "spine_03", "spine_04", "spine_05",
                      "clavicle_l", "upperarm_l", "thigh_l", "calf_l", "foot_l", "ball_l"});
  const auto gu = animator::guess_body_parts(*ue5);
  EXPECT_EQ(gu.convention, "unreal");
  EXPECT_EQ(ue5->link_name[part(gu, BodyPart::kChest)], "spine_05");
  EXPECT_EQ(ue5->link_name[part(gu, BodyPart::kLeftToes)], "ball_l");
  // Blender's metarig: "spine" is the hips, "spine.001" the spine
  const auto meta = named_skeleton({"spine", "spine.001", "spine.002", "spine.003", "spine.004",
                                    "spine.005", "spine.006", "thigh.L", "shin.L", "foot.L"});
  const auto gm = animator::guess_body_parts(*meta);
  EXPECT_EQ(gm.convention, "rigify");
  EXPECT_EQ(meta->link_name[part(gm, BodyPart::kHips)], "spine");
  EXPECT_EQ(meta->link_name[part(gm, BodyPart::kSpine)], "spine.001");
  EXPECT_EQ(meta->link_name[part(gm, BodyPart::kHead)], "spine.006");
  // ... and Blender's older metarig named its spine hips, spine, chest, neck, head
  const auto old_meta = named_skeleton({"hips", "spine", "chest", "neck", "head", "thigh.L",
                                        "shin.L", "foot.L", "upper_arm.L", "forearm.L"});
  const auto go = animator::guess_body_parts(*old_meta);
  EXPECT_EQ(go.convention, "rigify");
  EXPECT_EQ(old_meta->link_name[part(go, BodyPart::kHips)], "hips");
  EXPECT_EQ(old_meta->link_name[part(go, BodyPart::kSpine)], "spine");
  EXPECT_EQ(old_meta->link_name[part(go, BodyPart::kChest)], "chest");
  // Unity's humanoid names: UpperChest over Chest, LeftShoulder the clavicle
  const auto unity =
      named_skeleton({"Hips", "Spine", "Chest", "UpperChest", "LeftShoulder", "LeftUpperArm",
                      "LeftLowerArm", "LeftUpperLeg", "LeftLowerLeg", "LeftFoot", "LeftToes"});
  const auto gv = animator::guess_body_parts(*unity);
  EXPECT_EQ(gv.convention, "vrm");
  EXPECT_EQ(unity->link_name[part(gv, BodyPart::kChest)], "UpperChest");
  EXPECT_EQ(unity->link_name[part(gv, BodyPart::kLeftClavicle)], "LeftShoulder");
  EXPECT_EQ(unity->link_name[part(gv, BodyPart::kLeftShin)], "LeftLowerLeg");
  // Daz Genesis 2 (no Bend links): the biped-like lThigh and lHand do not make it a Biped, and
  // the root "hip" is the hips, not the "pelvis" below it
  const auto g2 =
      named_skeleton({"hip", "pelvis", "lThigh", "lShin", "lFoot", "lToe", "abdomen", "abdomen2",
                      "chest", "neck", "head", "lCollar", "lShldr", "lForeArm", "lHand"});
  const auto gd = animator::guess_body_parts(*g2);
  EXPECT_EQ(gd.convention, "daz");
  EXPECT_EQ(g2->link_name[part(gd, BodyPart::kHips)], "hip");
  EXPECT_EQ(g2->link_name[part(gd, BodyPart::kLeftUpperArm)], "lShldr");
  EXPECT_EQ(g2->link_name[part(gd, BodyPart::kChest)], "chest");
  // SMPL's short names: the ankle is the foot, the foot the toes, the shoulder the upper arm
  const auto smpl = named_skeleton({"Pelvis", "L_Hip", "L_Knee", "L_Ankle", "L_Foot", "Spine1",
                                    "Spine2", "Spine3", "Neck", "Head", "L_Collar", "L_Shoulder",
                                    "L_Elbow", "L_Wrist", "L_Hand"});
  const auto gs = animator::guess_body_parts(*smpl);
  EXPECT_EQ(gs.convention, "smpl");
  EXPECT_EQ(smpl->link_name[part(gs, BodyPart::kLeftFoot)], "L_Ankle");
  EXPECT_EQ(smpl->link_name[part(gs, BodyPart::kLeftToes)], "L_Foot");
  EXPECT_EQ(smpl->link_name[part(gs, BodyPart::kLeftUpperArm)], "L_Shoulder");
  EXPECT_EQ(smpl->link_name[part(gs, BodyPart::kLeftHand)], "L_Wrist");
  EXPECT_EQ(smpl->link_name[part(gs, BodyPart::kChest)], "Spine3");
}

TEST(JointNames, MappingOverridesGuessesAndNamesBadEntries) {
  const auto src = named_skeleton({"Hips", "LowerBack", "Spine", "LeftShoulder", "LeftArm",
                                   "LeftForeArm", "LeftHand", "LeftUpLeg", "LeftLeg"});
  const auto fig = core::build_human_figure({});
  animator::Correspondence c = animator::guess_correspondence(*src, *fig);
  const int arm = src->link_index("LeftArm"), hand = src->link_index("LeftHand");
  EXPECT_EQ(c.target_of_source[arm], fig->link_index("l_uarm"));
  animator::apply_mapping(*src, *fig, {{"LeftHand", std::nullopt}, {"LeftArm", "r_uarm"}},
                          "map.json", c);
  EXPECT_EQ(c.target_of_source[hand], -1);
  EXPECT_EQ(c.target_of_source[arm], fig->link_index("r_uarm"));
  EXPECT_EQ(c.source_of_target[fig->link_index("l_uarm")], -1);
  try {
    animator::apply_mapping(*src, *fig, {{"Nope", "l_hand"}}, "map.json", c);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("map.json: \"Nope\""), std::string::npos) << e.what();
  }
  EXPECT_THROW(animator::apply_mapping(*src, *fig, {{"LeftArm", "wing"}}, "map.json", c),
               std::invalid_argument);
  EXPECT_THROW(animator::apply_mapping(*src, *fig, {{"LeftArm", "l_hand"}, {"LeftHand", "l_hand"}},
                                       "map.json", c),
               std::invalid_argument);
}

}  // namespace
