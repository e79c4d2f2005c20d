// Tests for server/apply_message.hpp: messages drive a session as its own calls would, and the
// session's errors come back named by message type and wire field, leaving the session unchanged.
#include "server/apply_message.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "animator/session_file.hpp"
#include "io/bundled_characters.hpp"
#include "server/protocol.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using animator::Session;
using nlohmann::json;
namespace s = server;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

s::Position position_of(const Session& session, const std::string& link) {
  const core::Vector3 p = session.kinematics().X_W[session.model().link_index(link)].p;
  return {p.x(), p.y(), p.z()};
}

// The message of the ProtocolError that applying `m` throws ("" when it applies).
std::string apply_refusal(Session& session, const s::ClientMessage& m) {
  try {
    s::apply(session, m);
  } catch (const s::ProtocolError& e) {
    return e.what();
  }
  return "";
}

TEST(ApplyMessage, MessagesDriveTheSessionAsItsOwnCallsDo) {
  Session by_message(fixtures::bundled_human48(), "human48");
  Session by_call(fixtures::bundled_human48(), "human48");
  const int foot = fixtures::bundled_human48()->link_index("l_foot");
  const int hand = fixtures::bundled_human48()->link_index("r_hand");
  const s::Position p = position_of(by_call, "r_hand");
  const core::Vector3 hand_W(p[0], p[1], p[2]);

  const std::vector<s::ClientMessage> messages = {
      s::Hello{.protocol = 1},
      s::Pin{.link = "l_foot", .mode = ik::TaskMode::kPose, .point = {0, 0, 0.05}},
      s::DragBegin{.link = "r_hand", .target = p, .point = {0, 0, 0}},
      s::DragMove{.seq = 1, .target = {p[0], p[1] + 0.05, p[2]}},
      s::DragEnd{},
      s::MovePin{.link = "l_foot", .target = {0, 0.05, 0}, .rotation = s::Rotation{2, 0, 0, 0}},
      s::SetSettings{.settings = {{"iterations", 3}}},
      s::SetEffects{.scene = {.gravity = true}},
      s::KeyInsert{.time = 0.0, .interpolation = animator::Interpolation::kLinear},
      s::KeyInsert{.time = 1.0},
      s::KeyMove{.index = 1, .time = 2.0},
      s::BakeKeys{.rate = 10},
      s::KeyDelete{.index = 0},
      s::SetLoop{.loop = false, .start = 0.5, .end = 1.5},
      s::SetSpeed{.speed = -0.5},
      s::SetFalloff{.seconds = 0.25},
      s::Seek{.time = 0.75},
      s::Play{},
      s::Pause{},
      s::Unpin{.link = "l_foot"},
      s::Undo{},
      s::Undo{},
      s::Redo{},
  };
  for (const s::ClientMessage& m : messages) {
    SCOPED_TRACE(s::message_type(m));
    s::apply(by_message, m);
  }

  by_call.pin(foot, ik::TaskMode::kPose, {0, 0, 0.05});
  by_call.drag_begin(hand, hand_W);
  by_call.drag_move(hand_W + core::Vector3(0, 0.05, 0));
  by_call.drag_end();
  by_call.move_pin(foot, {0, 0.05, 0}, core::Quaternion::Identity());
  ik::SolverSettings settings = by_call.solver_settings();
  settings.iterations = 3;
  by_call.set_solver_settings(settings);
  by_call.set_scene({.gravity = true});
  by_call.key_insert(0.0, animator::Interpolation::kLinear);
  by_call.key_insert(1.0);
  by_call.key_move(1, 2.0);
  by_call.bake_keys(10);
  by_call.key_delete(0);
  by_call.set_loop(false, 0.5, 1.5);
  by_call.set_speed(-0.5);
  by_call.set_edit_falloff(0.25);
  by_call.seek(0.75);
  by_call.play();
  by_call.pause();
  by_call.unpin(foot);
  by_call.undo();
  by_call.undo();
  by_call.redo();

  EXPECT_EQ(animator::session_to_json(by_message), animator::session_to_json(by_call));
  EXPECT_EQ(by_message.history().undo_labels(), by_call.history().undo_labels());
  EXPECT_EQ(by_message.playback(), by_call.playback());
}

TEST(ApplyMessage, LayersAreMutedReweightedAndRemoved) {
  Session session(fixtures::bundled_human48(), "human48");
  core::Clip clip;
  clip.frame_time = 0.1;
  clip.frames.assign(10, session.q());
  session.set_clip(clip);
  // an edit during playback makes a layer
  const s::Position p = position_of(session, "r_hand");
  s::apply(session, s::Play{});
  s::apply(session, s::DragBegin{.link = "r_hand", .target = p});
  s::apply(session, s::DragMove{.seq = 1, .target = {p[0], p[1] + 0.1, p[2]}});
  session.tick(0.05);
  s::apply(session, s::DragEnd{});
  s::apply(session, s::Pause{});
  ASSERT_EQ(session.layers().size(), 1u);
  s::apply(session, s::Layer{.index = 0, .muted = true});
  EXPECT_TRUE(session.layers()[0]->muted);
  s::apply(session, s::Layer{.index = 0, .weight = 0.5});
  EXPECT_EQ(session.layers()[0]->weight, 0.5);
  s::apply(session, s::Layer{.index = 0, .remove = true});
  EXPECT_TRUE(session.layers().empty());
  EXPECT_EQ(apply_refusal(session, s::Layer{.index = 0}),
            "layer.muted: one of muted, weight or remove is required");
}

TEST(ApplyMessage, SessionErrorsComeBackNamedByTypeAndField) {
  Session session(fixtures::bundled_human48(), "human48");
  const std::vector<std::pair<s::ClientMessage, std::string>> cases = {
      {s::Pin{.link = "tail"}, "pin.link: no link named \"tail\""},
      {s::DragBegin{.link = "nose"}, "drag_begin.link: no link named \"nose\""},
      {s::DragBegin{.link = "r_hand", .target = {kNaN, 0, 0}},
       "drag_begin.target: must be 3 finite numbers"},
      {s::DragBegin{.link = "r_hand", .point = {0, kNaN, 0}},
       "drag_begin.point: must be 3 finite numbers"},
      {s::DragMove{.seq = 1}, "drag_move: no drag in progress (drag_begin first)"},
      {s::Unpin{.link = "l_foot"}, "unpin.link: link 'l_foot' is not pinned"},
      {s::MovePin{.link = "l_foot"}, "move_pin.link: link 'l_foot' is not pinned"},
      {s::SetSettings{.settings = {{"iterations", "many"}}},
       "set_settings.settings/iterations: expected an integer"},
      {s::SetSettings{.settings = {{"damping", -1}}}, "set_settings.settings: "},
      {s::KeyInsert{.time = -1}, "key_insert.time: must be a finite time >= 0"},
      {s::KeyDelete{.index = 0}, "key_delete.index: no key 0"},
      {s::KeyMove{.index = 3, .time = 1}, "key_move.index: no key 3"},
      {s::BakeKeys{}, "bake_keys: there are no keys to bake"},
      {s::Seek{.time = kNaN}, "seek.time: must be a finite number"},
      {s::SetLoop{.loop = true, .start = -1}, "set_loop.start: needs 0 <= start <= end"},
      {s::SetLoop{.loop = true, .start = 2, .end = 1}, "set_loop.end: needs 0 <= start <= end"},
      {s::SetSpeed{.speed = 1000}, "set_speed.speed: must be in [-100, 100]"},
      {s::Layer{.index = 0, .muted = true}, "layer.index: no layer 0"},
      {s::BakeLayers{}, "bake_layers: there is no clip to bake the layers into"},
      {s::SetFalloff{.seconds = 100}, "set_falloff.seconds: must be in [0, 60]"},
  };
  const json before = animator::session_to_json(session);
  for (const auto& [message, expected] : cases) {
    EXPECT_EQ(apply_refusal(session, message).rfind(expected, 0), 0u)
        << s::message_type(message) << ": " << apply_refusal(session, message);
  }
  EXPECT_EQ(animator::session_to_json(session), before);
  EXPECT_EQ(session.history().size(), 0u);

  // with a key and a drag in progress, the rate and the rotation are at fault
  s::apply(session, s::KeyInsert{.time = 0});
  EXPECT_EQ(apply_refusal(session, s::BakeKeys{.rate = 0}), "bake_keys.rate: must be in (0, 1000]");
  s::apply(session, s::DragBegin{.link = "r_hand", .target = position_of(session, "r_hand")});
  EXPECT_EQ(apply_refusal(session, s::DragMove{.seq = 2, .rotation = s::Rotation{kNaN, 0, 0, 0}}),
            "drag_move.rotation: must be a unit quaternion [w, x, y, z]");
}

TEST(ApplyMessage, IntegersAreRangeCheckedNeverWrapped) {
  // 2^32 + 1 is 1 as a 32-bit integer: each integer field is refused naming its field and range
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"type": "set_settings", "settings": {"iterations": 4294967297}})",
       "set_settings.settings/iterations: 4294967297 is out of range (rule: an integer in [1, "
       "1000])"},
      {R"({"type": "set_settings", "settings": {"iterations": 0}})",
       "set_settings.settings/iterations: 0 is out of range (rule: an integer in [1, 1000])"},
      {R"({"type": "key_delete", "index": 4294967297})",
       "key_delete.index: 4294967297 is out of range (rule: an integer in [0, 2147483647])"},
      {R"({"type": "key_move", "index": -4294967295, "time": 1})",
       "key_move.index: -4294967295 is out of range (rule: an integer in [0, 2147483647])"},
      {R"({"type": "drag_move", "seq": 4294967297, "target": [0, 0, 0]})",
       "drag_move.seq: 4294967297 is out of range (rule: an integer in [0, 4294967295])"},
      {R"({"type": "hello", "protocol": 4294967297})",
       "hello.protocol: 4294967297 is out of range (rule: an integer in [0, 2147483647])"},
  };
  Session session(fixtures::bundled_human48(), "human48");
  const json before = animator::session_to_json(session);
  for (const auto& [text, expected] : cases) {
    std::string message;
    try {
      s::apply(session, s::parse_client_message(text).message);
    } catch (const s::ProtocolError& e) {
      message = e.what();
    }
    EXPECT_EQ(message, expected) << text;
  }
  EXPECT_EQ(animator::session_to_json(session), before);
}

}  // namespace
