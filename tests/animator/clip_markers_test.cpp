// Tests for the markers of a fitted trial kept beside its clip (animator/clip_markers.hpp): they
// ride with the clip through undo and redo, go when another clip replaces it, stay through a bake
// of the layers, must match the clip frame for frame, and are kept bit for bit by the journal's
// changes and by the session file, whose broken marker fields are named.
#include "animator/clip_markers.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "animator/document_changes.hpp"
#include "animator/document_json.hpp"
#include "animator/session.hpp"
#include "animator/session_file.hpp"
#include "core/configuration.hpp"
#include "tests/animator/animator_fixtures.hpp"

namespace {

using namespace animator;
using animator_test::human;
using animator_test::session_file_error;
using nlohmann::json;

constexpr int kFrames = 5;
constexpr double kRate = 120.0;

core::Clip clip_of(const core::Model& m, int frames = kFrames, double lift = 0.0) {
  core::Clip clip;
  clip.frame_time = 1.0 / kRate;
  for (int f = 0; f < frames; ++f) {
    Eigen::VectorXd q = core::neutral_configuration(m);
    q[1] += lift + 0.01 * f;  // the root rises a centimetre a frame
    clip.frames.push_back(q);
  }
  return clip;
}

// three markers (pelvis, left foot, right hand) over `frames` frames; the foot is missing in
// frame 2
std::shared_ptr<const ClipMarkers> markers_of(const core::Model& m, int frames = kFrames) {
  ik::MarkerSet set;
  set.markers = {{"LASI", m.link_index("pelvis"), core::Vector3(0.1, 0.05, 0.12)},
                 {"LHEE", m.link_index("l_foot"), core::Vector3(0.0, -0.05, -0.07)},
                 {"RFIN", m.link_index("r_hand"), core::Vector3(0.0, -0.08, 0.0)}};
  ik::MarkerTrajectories t;
  t.rate_hz = kRate;
  t.frames = frames;
  t.markers = 3;
  for (int f = 0; f < frames; ++f) {
    for (int k = 0; k < 3; ++k) {
      const bool present = !(f == 2 && k == 1);
      // values that are not short decimals, so bit-for-bit round trips are tested
      t.positions.push_back(present ? core::Vector3(0.1 * k + 1.0 / 3.0, 0.9 + f / 7.0, -0.2 / 3.0)
                                    : core::Vector3::Zero());
      t.present.push_back(present ? 1 : 0);
    }
  }
  return make_clip_markers(m, set, t);
}

void expect_same_markers(const ClipMarkers& a, const ClipMarkers& b) {
  ASSERT_EQ(a.set.size(), b.set.size());
  for (int k = 0; k < a.set.size(); ++k) {
    EXPECT_EQ(a.set.markers[k].name, b.set.markers[k].name);
    EXPECT_EQ(a.set.markers[k].link, b.set.markers[k].link);
    EXPECT_EQ(a.set.markers[k].offset, b.set.markers[k].offset);
  }
  EXPECT_EQ(a.measured.rate_hz, b.measured.rate_hz);
  EXPECT_EQ(a.measured.frames, b.measured.frames);
  EXPECT_EQ(a.measured.present, b.measured.present);
  EXPECT_EQ(a.measured.positions, b.measured.positions);
}

TEST(ClipMarkers, RideWithTheirClipThroughUndoRedoAndABake) {
  Session s(human(), "human48");
  const auto markers = markers_of(s.model());
  s.set_clip(clip_of(s.model()), "import clip", markers);
  ASSERT_EQ(s.clip_markers(), markers.get());

  s.set_clip(clip_of(s.model(), 7), "import clip");
  EXPECT_EQ(s.clip_markers(), nullptr) << "another clip keeps the trial's markers";
  ASSERT_TRUE(s.undo());
  EXPECT_EQ(s.clip_markers(), markers.get()) << "undo brings the fitted clip without its markers";
  EXPECT_EQ(s.clip()->size(), kFrames);
  ASSERT_TRUE(s.redo());
  EXPECT_EQ(s.clip_markers(), nullptr);
  ASSERT_TRUE(s.undo());

  s.bake_layers();  // same frames, same rate: the markers still describe the clip
  EXPECT_EQ(s.clip_markers(), markers.get());
}

TEST(ClipMarkers, MarkersThatDoNotMatchTheClipAreRefusedAndTheSessionKeepsItsClip) {
  Session s(human(), "human48");
  s.set_clip(clip_of(s.model()), "import clip", markers_of(s.model()));
  const core::Clip* before = s.clip();
  try {
    s.set_clip(clip_of(s.model(), 6), "import clip", markers_of(s.model(), kFrames));
    FAIL() << "6 frames with markers for 5 were taken";
  } catch (const SessionError& e) {
    EXPECT_EQ(std::string(e.what()), "markers: markers have 5 frames, the clip 6");
  }
  EXPECT_EQ(s.clip(), before);
  ASSERT_NE(s.clip_markers(), nullptr);

  // markers of another figure (a link index this one lacks) are refused too
  auto other = std::make_shared<ClipMarkers>(*s.clip_markers());
  other->set.markers[0].link = s.model().njoints + 3;
  EXPECT_THROW(s.set_clip(clip_of(s.model()), "import clip", other), SessionError);
}

TEST(ClipMarkers, TheJournalAndTheSessionFileKeepThemBitForBit) {
  Session s(human(), "human48");
  const Document before = s.document();
  const Playback playback = s.playback();
  s.set_clip(clip_of(s.model()), "import clip", markers_of(s.model()));

  // the journal: the changes from before to after, applied to before
  const json changes = document_changes(s.model(), before, playback, s.document(), s.playback());
  ASSERT_TRUE(changes.contains("markers"));
  EXPECT_TRUE(changes["markers"]["frames"][2][3].is_null()) << "the missing sample is a number";
  Document replayed = before;
  Playback replayed_playback = playback;
  apply_document_changes(s.model(), changes, replayed, replayed_playback);
  ASSERT_NE(replayed.markers, nullptr);
  expect_same_markers(*replayed.markers, *s.clip_markers());
  EXPECT_NE(replayed.markers->revision, s.clip_markers()->revision);

  // a later clip without markers writes "markers": null
  const Document fitted = s.document();
  s.set_clip(clip_of(s.model(), 3), "import clip");
  const json cleared = document_changes(s.model(), fitted, playback, s.document(), s.playback());
  ASSERT_TRUE(cleared.contains("markers"));
  EXPECT_TRUE(cleared["markers"].is_null());
  ASSERT_TRUE(s.undo());

  // the session file
  const auto restored = session_from_json(session_to_json(s), "test.json");
  ASSERT_NE(restored->clip_markers(), nullptr);
  expect_same_markers(*restored->clip_markers(), *s.clip_markers());
}

TEST(ClipMarkers, BrokenMarkerFieldsOfASessionFileAreNamed) {
  Session s(human(), "human48");
  s.set_clip(clip_of(s.model()), "import clip", markers_of(s.model()));
  const json good = session_to_json(s);
  ASSERT_EQ(session_file_error(good), "");
  json j = good;
  j["markers"]["frames"][1][4] = nullptr;
  EXPECT_EQ(session_file_error(j), "/markers/frames/1: marker 1: part of a sample is null");
  j = good;
  j["markers"]["frames"][3].erase(0);
  EXPECT_EQ(session_file_error(j),
            "/markers/frames/3: expected 9 numbers or nulls (three per marker)");
  j = good;
  j["markers"]["markers"][2]["link"] = "r_paw";
  EXPECT_EQ(session_file_error(j), "/markers/markers/2/link: unknown link 'r_paw'");
  j = good;
  j["markers"]["frames"].erase(4);
  EXPECT_EQ(session_file_error(j), "/markers: markers have 4 frames, the clip 5");
  j = good;
  j["clip"] = nullptr;
  EXPECT_EQ(session_file_error(j),
            "/markers: markers without a clip (rule: markers ride on the clip fitted to them)");
  j = good;
  j["markers"]["rate"] = 0;
  EXPECT_EQ(session_file_error(j), "/markers: rate must be positive and finite");
  j = good;
  j.erase("markers");  // a file written before markers were kept
  EXPECT_EQ(session_file_error(j), "");
}

}  // namespace
