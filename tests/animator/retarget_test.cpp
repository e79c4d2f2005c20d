// Retargeting (animator/retarget.hpp) of the shared captures onto the bundled figures: feet held
// during contacts, joint ranges respected, bone lengths the target's, and a round trip back onto
// the capture skeleton that keeps hands, feet and head where they were.
#include "animator/retarget.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "io/bvh.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using animator::BodyPart;

struct Case {
  const char* file;
  int dof;
};

std::string bvh_path(const char* file) { return fixtures::data_dir() + "/bvh/" + file; }

std::shared_ptr<const core::Model> figure(int dof) {
  core::HumanFigureOptions o;
  o.dof = dof;
  return core::build_human_figure(o);
}

class RetargetCapture : public ::testing::TestWithParam<Case> {};

TEST_P(RetargetCapture, FeetHoldRangesHoldBonesAreTheTargets) {
  PINDRAG_REQUIRE_DATA_DIR();
  const Case k = GetParam();
  const io::BvhImport src = io::load_bvh_file(bvh_path(k.file));
  const auto target = figure(k.dof);
  const animator::RetargetResult r = animator::retarget(*src.model, src.clip, *target);
  const animator::RetargetReport& rep = r.report;
  std::cout << k.file << " -> human" << k.dof << ": " << rep.contacts.size()
            << " contacts, max slide " << 1000 * rep.max_foot_slide << " mm, range violation "
            << rep.max_range_violation << " rad (" << rep.frames_out_of_range
            << " frames), effector error " << 1000 * rep.max_effector_error << " mm, scale "
            << rep.scale << ", conventions " << rep.source_convention << " -> "
            << rep.target_convention << "\n";

  ASSERT_EQ(r.clip.size(), src.clip.size());
  EXPECT_EQ(r.clip.frame_time, src.clip.frame_time);
  EXPECT_EQ(core::check_clip(*target, r.clip), "");
  // a walk stands on its feet: both feet have contacts, each held within 1 cm
  int left = 0, right = 0;
  for (const animator::FootContact& c : rep.contacts) {
    const std::string& name = target->link_name[c.target_link];
    left += name[0] == 'l';
    right += name[0] == 'r';
    EXPECT_LE(c.slide, 0.01) << name << " frames " << c.first << ".." << c.last;
  }
  EXPECT_GT(left, 0);
  EXPECT_GT(right, 0);
  EXPECT_LE(rep.max_foot_slide, 0.01);
  // hands, head and feet within 5 cm of where the source's bones put them in every frame: a foot
  // turned out further than the ankle allows turns the leg (the swivel) instead of holding the
  // pelvis back from the source's hips
  EXPECT_LE(rep.max_effector_error, 0.05);
  // the target's joint ranges
  EXPECT_EQ(rep.frames_out_of_range, 0) << "largest violation " << rep.max_range_violation;
  // bone lengths: every link sits at its rest offset from its parent, in every frame
  core::Data d(*target);
  for (int f = 0; f < r.clip.size(); f += 7) {
    core::forward_kinematics(*target, d, r.clip.frames[f]);
    for (int i = 2; i < target->njoints; ++i) {
      const double bone = (d.X_W[i].p - d.X_W[target->parent[i]].p).norm();
      ASSERT_NEAR(bone, target->X_PJ[i].p.norm(), 1e-9) << target->link_name[i] << " frame " << f;
    }
  }
  // during contacts the feet are as high as the source's, scaled by the leg-length ratio: on the
  // floor when the source's are, up on the toes when the source crouches on them
  core::Data ds(*src.model);
  for (const animator::FootContact& c : rep.contacts) {
    const int mid = (c.first + c.last) / 2;
    core::forward_kinematics(*target, d, r.clip.frames[mid]);
    core::forward_kinematics(*src.model, ds, src.clip.frames[mid]);
    const double source_height = ds.X_W[c.source_link].p.y();
    EXPECT_LT(d.X_W[c.target_link].p.y(), rep.scale * source_height + 0.05)
        << target->link_name[c.target_link] << " frame " << mid << ", source at " << source_height;
  }
}

// A → B → A: hands, feet and head of the capture skeleton come back within 2 cm, times the
// ratio of the two skeletons' leg lengths (the size of B's errors seen on A)
// Not met yet, so not run (docs/retargeting.md, "Open"): the worst effector comes back 41–136 mm
// off against about 19 mm; with every range of human48 removed, still 24–34 mm. Enable it when
// the round trip reaches the figure.
TEST_P(RetargetCapture, DISABLED_RoundTripKeepsEndEffectors) {
  PINDRAG_REQUIRE_DATA_DIR();
  const Case k = GetParam();
  const io::BvhImport src = io::load_bvh_file(bvh_path(k.file));
  const auto target = figure(k.dof);
  const animator::RetargetResult there = animator::retarget(*src.model, src.clip, *target);
  const animator::RetargetResult back = animator::retarget(*target, there.clip, *src.model);
  ASSERT_EQ(back.clip.size(), src.clip.size());
  const animator::Correspondence c = animator::guess_correspondence(*src.model, *target);
  const double tolerance = 0.02 / there.report.scale;
  double worst = 0;
  std::string worst_link;
  core::Data a(*src.model), b(*src.model);
  for (int f = 0; f < src.clip.size(); ++f) {
    core::forward_kinematics(*src.model, a, src.clip.frames[f]);
    core::forward_kinematics(*src.model, b, back.clip.frames[f]);
    for (BodyPart p : {BodyPart::kLeftHand, BodyPart::kRightHand, BodyPart::kLeftFoot,
                       BodyPart::kRightFoot, BodyPart::kHead}) {
      const int s = c.source_parts.link[static_cast<int>(p)];
      ASSERT_GE(s, 0) << to_string(p);
      const double e = (a.X_W[s].p - b.X_W[s].p).norm();
      if (e > worst)
        worst = e, worst_link = src.model->link_name[s] + " frame " + std::to_string(f);
    }
  }
  std::cout << k.file << " -> human" << k.dof << " -> back: worst end effector " << 1000 * worst
            << " mm (" << worst_link << "), tolerance " << 1000 * tolerance << " mm\n";
  EXPECT_LE(worst, tolerance) << worst_link;
}

INSTANTIATE_TEST_SUITE_P(Captures,
                         RetargetCapture,
                         ::testing::Values(Case{"cmu_walk_cgspeed.bvh", 48},
                                           Case{"cmu_walk_cgspeed.bvh", 34},
                                           Case{"cmu_131_01_mj_walk_3dsmax.bvh", 48},
                                           Case{"cmu_131_01_mj_walk_3dsmax.bvh", 34},
                                           Case{"mixamo_naming_freebvh.bvh", 48},
                                           Case{"mixamo_naming_freebvh.bvh", 34}),
                         [](const auto& param_info) {
                           std::string n = param_info.param.file;
                           n = n.substr(0, n.find('.'));
                           return n + "_human" + std::to_string(param_info.param.dof);
                         });

}  // namespace
