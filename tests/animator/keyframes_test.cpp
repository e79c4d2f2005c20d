// Tests for animator/keyframes.hpp: the key track (insert, replace, move, find), sampling by
// interpolation mode, copies that share their keys, and the differences undo stores.
#include "animator/keyframes.hpp"

#include <gtest/gtest.h>

#include <random>

#include "core/configuration.hpp"
#include "tests/animator/animator_fixtures.hpp"

namespace {

using animator::diff_keys;
using animator::Interpolation;
using animator::KeyChange;
using animator::Keyframe;
using animator::KeyTrack;
using animator_test::human;

Keyframe key(double t, int seed, Interpolation i = Interpolation::kSmooth) {
  return Keyframe{t, core::random_configuration(*human(), static_cast<std::uint64_t>(seed)), i};
}

std::vector<double> times(const KeyTrack& k) {
  std::vector<double> out;
  for (const Keyframe& f : k.keys()) out.push_back(f.time);
  return out;
}

TEST(KeyTrack, KeysStaySortedAndOnePerTime) {
  KeyTrack k;
  EXPECT_EQ(k.insert(key(1.0, 1)), 0);
  EXPECT_EQ(k.insert(key(0.5, 2)), 0);
  EXPECT_EQ(k.insert(key(2.0, 3)), 2);
  EXPECT_EQ(k.insert(key(1.0 + 5e-10, 4)), 1);  // within 1e-9 s: replaces
  EXPECT_EQ(times(k), (std::vector<double>{0.5, 1.0 + 5e-10, 2.0}));
  EXPECT_EQ(k.keys()[1].q, key(0, 4).q);
  EXPECT_EQ(k.find(1.0), 1);
  EXPECT_EQ(k.find(1.5), -1);
  EXPECT_EQ(k.move(0, 3.0), 2);
  EXPECT_EQ(times(k), (std::vector<double>{1.0 + 5e-10, 2.0, 3.0}));
  EXPECT_EQ(k.move(0, 2.0), 0);  // onto another key: replaces it
  EXPECT_EQ(k.size(), 2);
  EXPECT_TRUE(k.remove(1));
  EXPECT_FALSE(k.remove(5));
  EXPECT_EQ(k.move(3, 1.0), -1);
  EXPECT_DOUBLE_EQ(k.duration(), 2.0);
}

TEST(KeyTrack, CopiesShareTheirKeysUntilOneChanges) {
  KeyTrack a;
  for (int i = 0; i < 100; ++i) a.insert(key(i * 0.1, i));
  const KeyTrack b = a;
  EXPECT_TRUE(a.shares_keys_with(b));
  EXPECT_EQ(&a.keys(), &b.keys());  // one vector, not a copy
  a.insert(key(20.0, 7));
  EXPECT_FALSE(a.shares_keys_with(b));
  EXPECT_EQ(b.size(), 100);
  EXPECT_EQ(a.size(), 101);
  EXPECT_TRUE(diff_keys(b, b).empty());
}

TEST(KeyTrack, SamplesByInterpolationMode) {
  const core::Model& m = *human();
  KeyTrack k;
  Eigen::VectorXd q;
  k.sample(m, 1.0, q);
  EXPECT_EQ(q, core::neutral_configuration(m));  // no keys: neutral
  const Keyframe a = key(1.0, 1, Interpolation::kStep), b = key(2.0, 2, Interpolation::kLinear);
  const Keyframe c = key(3.0, 3);
  k.insert(a);
  k.insert(b);
  k.insert(c);
  k.sample(m, 0.0, q);
  EXPECT_EQ(q, a.q);  // before the first: the first
  k.sample(m, 9.0, q);
  EXPECT_EQ(q, c.q);  // after the last: the last
  k.sample(m, 1.7, q);
  EXPECT_EQ(q, a.q);  // step holds
  k.sample(m, 2.5, q);
  Eigen::VectorXd half;
  core::interpolate(m, b.q, c.q, 0.5, half);
  EXPECT_TRUE(q.isApprox(half, 1e-12));  // linear: the geodesic midpoint
  k.sample(m, 2.0, q);
  EXPECT_EQ(q, b.q);  // exactly on a key: the key
  EXPECT_TRUE(core::check_configuration(m, q).empty());
}

TEST(KeyTrack, SmoothInterpolationPassesThroughItsKeysAndStaysValid) {
  const core::Model& m = *human();
  KeyTrack k;
  for (int i = 0; i < 5; ++i) k.insert(key(i * 0.5, 10 + i));
  Eigen::VectorXd q;
  for (int i = 0; i < 5; ++i) {
    k.sample(m, i * 0.5 + 1e-12, q);
    EXPECT_LT((q - k.keys()[i].q).cwiseAbs().maxCoeff(), 1e-9) << i;
  }
  for (double t = 0; t < 2.0; t += 0.07) {
    k.sample(m, t, q);
    EXPECT_TRUE(core::check_configuration(m, q).empty()) << t;
  }
}

// A random edit of a track: insert, replace, remove, move or change an interpolation.
void random_edit(KeyTrack& k, std::mt19937& rng, int& seed) {
  const int n = k.size();
  switch (n == 0 ? 0 : rng() % 4) {
    case 0:
      k.insert(key(0.25 * (rng() % 40), ++seed));
      break;
    case 1:
      k.remove(static_cast<int>(rng() % n));
      break;
    case 2:
      k.move(static_cast<int>(rng() % n), 0.25 * (rng() % 40));
      break;
    default: {
      Keyframe f = k.keys()[rng() % n];
      f.interpolation = Interpolation::kLinear;
      k.insert(f);
    }
  }
}

TEST(KeyTrack, DifferencesApplyForwardAndBackwardExactly) {
  std::mt19937 rng(7);
  int seed = 0;
  KeyTrack track;
  for (int e = 0; e < 500; ++e) {
    const KeyTrack before = track;
    const int edits = 1 + static_cast<int>(rng() % 3);
    for (int i = 0; i < edits; ++i) random_edit(track, rng, seed);
    const KeyChange change = diff_keys(before, track);
    KeyTrack forward = before, backward = track;
    forward.apply(change, true);
    backward.apply(change, false);
    ASSERT_EQ(forward.keys(), track.keys()) << e;
    ASSERT_EQ(backward.keys(), before.keys()) << e;
    // a change holds only what changed: never more keys than the edits touched
    EXPECT_LE(change.removed.size() + change.added.size(), static_cast<size_t>(3 * edits)) << e;
  }
}

TEST(KeyTrack, ComposedDifferencesEqualTheDirectOne) {
  std::mt19937 rng(11);
  int seed = 0;
  KeyTrack a;
  for (int e = 0; e < 300; ++e) {
    KeyTrack b = a;
    random_edit(b, rng, seed);
    KeyTrack c = b;
    random_edit(c, rng, seed);
    const KeyChange composed = animator::compose(diff_keys(a, b), diff_keys(b, c));
    const KeyChange direct = diff_keys(a, c);
    ASSERT_EQ(composed.removed, direct.removed) << e;
    ASSERT_EQ(composed.added, direct.added) << e;
    a = c;
  }
}

TEST(KeyTrack, AChangeCountsTheBytesOfItsKeys) {
  KeyChange c;
  EXPECT_EQ(c.bytes(), 0u);
  c.added.push_back(key(1.0, 1));
  EXPECT_GE(c.bytes(), sizeof(Keyframe) + sizeof(double) * human()->nq);
  EXPECT_LT(c.bytes(), 2 * (sizeof(Keyframe) + sizeof(double) * human()->nq));
}

}  // namespace
