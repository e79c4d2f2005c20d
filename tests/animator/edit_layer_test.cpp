// Tests for animator/edit_layer.hpp: the blend window and its falloff, layered frames that are
// bit-identical to the clip outside it, sampling between frames, and baking.
#include "animator/edit_layer.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "core/configuration.hpp"
#include "tests/animator/animator_fixtures.hpp"

namespace {

using animator::EditLayer;
using animator::LayerStack;
using animator_test::human;
using animator_test::swinging_clip;

// A layer displacing frames [first, first + n) by a constant twist of every coordinate.
std::shared_ptr<EditLayer> layer(const core::Model& m, int first, int n, double amount) {
  auto l = std::make_shared<EditLayer>();
  l->name = "edit";
  l->first_frame = first;
  l->falloff = 0.2;
  l->displacement.assign(n, Eigen::VectorXd::Constant(m.nv, amount));
  return l;
}

bool bit_identical(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

TEST(EditLayer, BlendIsTheWeightInsideACosineRampOverTheFalloffAndZeroBeyond) {
  EditLayer l = *layer(*human(), 10, 5, 0.1);
  l.weight = 0.8;
  const double ft = 1.0 / 30;  // falloff 0.2 s = 6 frames
  EXPECT_EQ(l.last_frame(), 14);
  for (int f = 10; f <= 14; ++f) EXPECT_EQ(l.blend(f, ft), 0.8) << f;
  EXPECT_NEAR(l.blend(7, ft), 0.8 * 0.5, 1e-12);   // half way through the falloff: half
  EXPECT_NEAR(l.blend(17, ft), 0.8 * 0.5, 1e-12);  // symmetric after the edit
  EXPECT_GT(l.blend(9, ft), l.blend(8, ft));       // rising toward the edit
  EXPECT_EQ(l.blend(4, ft), 0.0);                  // 6 frames away: exactly 0
  EXPECT_EQ(l.blend(40, ft), 0.0);
  l.muted = true;
  EXPECT_EQ(l.blend(12, ft), 0.0);
  l.muted = false;
  l.falloff = 0;
  EXPECT_EQ(l.blend(9, ft), 0.0);  // no falloff: a hard edge
}

TEST(EditLayer, FramesOutsideTheWindowAreTheClipBitForBit) {
  const core::Model& m = *human();
  const core::Clip base = swinging_clip(m, 60);
  const LayerStack layers{layer(m, 20, 10, 0.05)};
  Eigen::VectorXd q;
  for (int f = 0; f < base.size(); ++f) {
    animator::layered_frame(m, base, layers, f, q);
    const bool outside = f <= 20 - 6 || f >= 29 + 6;  // 6 frames away: blend 0
    if (outside) {
      EXPECT_TRUE(bit_identical(q, base.frames[f])) << f;
    } else {
      EXPECT_FALSE(bit_identical(q, base.frames[f])) << f;
      EXPECT_TRUE(core::check_configuration(m, q).empty()) << f;
    }
  }
  // inside the edit: the clip frame ⊕ the displacement
  animator::layered_frame(m, base, layers, 25, q);
  EXPECT_TRUE(q.isApprox(core::integrate(m, base.frames[25], layers[0]->displacement[5], 1.0)));
}

TEST(EditLayer, LayersApplyInOrderAndMutedOnesNotAtAll) {
  const core::Model& m = *human();
  const core::Clip base = swinging_clip(m, 30);
  auto a = layer(m, 5, 10, 0.05), b = layer(m, 5, 10, -0.02);
  Eigen::VectorXd both, expected;
  animator::layered_frame(m, base, {a, b}, 8, both);
  core::integrate(m, base.frames[8], a->displacement[3], 1.0, expected);
  core::integrate(m, expected, b->displacement[3], 1.0, expected);
  EXPECT_TRUE(both.isApprox(expected, 1e-14));
  b->muted = true;
  Eigen::VectorXd only_a;
  animator::layered_frame(m, base, {a, b}, 8, only_a);
  animator::layered_frame(m, base, {a}, 8, expected);
  EXPECT_TRUE(bit_identical(only_a, expected));
}

TEST(EditLayer, SamplingBetweenFramesInterpolatesTheLayeredFrames) {
  const core::Model& m = *human();
  const core::Clip base = swinging_clip(m, 30);
  const LayerStack layers{layer(m, 10, 5, 0.05)};
  Eigen::VectorXd a, b, mid, got;
  animator::layered_frame(m, base, layers, 11, a);
  animator::layered_frame(m, base, layers, 12, b);
  core::interpolate(m, a, b, 0.25, mid);
  animator::sample_layered(m, base, layers, 11.25 * base.frame_time, got);
  EXPECT_TRUE(got.isApprox(mid, 1e-12));
  animator::sample_layered(m, base, layers, 12 * base.frame_time, got);
  EXPECT_TRUE(got.isApprox(b, 1e-14));
  animator::sample_layered(m, base, layers, -1.0, got);  // clamped to the first frame
  EXPECT_TRUE(bit_identical(got, base.frames[0]));
  animator::sample_layered(m, core::Clip{}, layers, 0.5, got);  // no frames: neutral
  EXPECT_EQ(got, core::neutral_configuration(m));
}

TEST(EditLayer, BakeIsEveryLayeredFrame) {
  const core::Model& m = *human();
  const core::Clip base = swinging_clip(m, 40);
  const LayerStack layers{layer(m, 3, 4, 0.1), layer(m, 30, 8, -0.05)};
  const core::Clip baked = animator::bake(m, base, layers);
  ASSERT_EQ(baked.size(), base.size());
  EXPECT_EQ(baked.frame_time, base.frame_time);
  Eigen::VectorXd q;
  for (int f = 0; f < base.size(); ++f) {
    animator::layered_frame(m, base, layers, f, q);
    EXPECT_TRUE(bit_identical(baked.frames[f], q)) << f;
  }
}

}  // namespace
