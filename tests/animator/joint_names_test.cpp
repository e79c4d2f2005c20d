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

TEST(JointNames, NormalizeDropsNamespacesBipedPrefixAndSeparators) {
  EXPECT_EQ(animator::normalize_joint_name("mixamorig:LeftArm"), "leftarm");
  EXPECT_EQ(animator::normalize_joint_name("Bip01 L UpperArm"), "lupperarm");
  EXPECT_EQ(animator::normalize_joint_name("Bip001 R Calf"), "rcalf");
  EXPECT_EQ(animator::normalize_joint_name("l_uarm"), "luarm");
  EXPECT_EQ(animator::normalize_joint_name("Bip01"), "bip01");
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
