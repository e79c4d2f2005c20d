#include "server/protocol.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "animator/session_file.hpp"
#include "io/bvh.hpp"

namespace server {
namespace {

using nlohmann::json;

json vec3(const core::Vector3& v) { return json::array({v.x(), v.y(), v.z()}); }
json quat(const core::Quaternion& q) { return json::array({q.w(), q.x(), q.y(), q.z()}); }

json limits_json(const core::Model& model, int i) {
  const core::JointType t = model.joint_type[i];
  if (t != core::JointType::kRevolute && t != core::JointType::kPrismatic) return nullptr;
  const core::JointLimits& l = model.limits[i];
  if (!std::isfinite(l.lower) || !std::isfinite(l.upper)) return nullptr;
  return json::array({l.lower, l.upper});
}

json range_json(const core::Model& model, int i) {
  if (model.joint_type[i] != core::JointType::kSpherical) return nullptr;
  const core::SphericalRange& r = model.spherical_range[i];
  if (r.empty()) return nullptr;
  json vertices = json::array();
  for (size_t k = 0; k < r.swing.size(); ++k) {
    vertices.push_back({r.swing[k].x(), r.swing[k].y(), r.twist_lower[k], r.twist_upper[k]});
  }
  json triangles = json::array();
  for (const auto& t : r.triangles) triangles.push_back({t[0], t[1], t[2]});
  return {{"frame", quat(r.frame)}, {"vertices", vertices}, {"triangles", triangles}};
}

json shapes_json(const core::Model& model, int i) {
  // visual primitives, else collision ones (as the thumbnail renderer draws them)
  auto primitive = [](const core::Geometry& g) { return g.shape != core::Geometry::Shape::kMesh; };
  const std::vector<core::Geometry>* list = &model.visual[i];
  if (std::none_of(list->begin(), list->end(), primitive)) list = &model.collision[i];
  json shapes = json::array();
  for (const core::Geometry& g : *list) {
    if (!primitive(g)) continue;
    shapes.push_back({{"shape", core::to_string(g.shape)},
                      {"radius", g.radius},
                      {"length", g.length},
                      {"size", vec3(g.size)},
                      {"p", vec3(g.X_LinkShape.p)},
                      {"R", quat(core::Quaternion(g.X_LinkShape.R))}});
  }
  return shapes;
}

void put_u16(std::string& b, size_t at, std::uint16_t v) { std::memcpy(b.data() + at, &v, 2); }
void put_u32(std::string& b, size_t at, std::uint32_t v) { std::memcpy(b.data() + at, &v, 4); }
void put_f32(std::string& b, size_t at, double v) {
  const auto f = static_cast<float>(v);
  std::memcpy(b.data() + at, &f, 4);
}

}  // namespace

json character_json(const core::Model& model, const std::string& name, bool skinned) {
  json links = json::array();
  double lowest = 0, highest = 0;
  for (int i = 1; i < model.njoints; ++i) {
    links.push_back(
        {{"name", model.link_name[i]},
         {"display_name", model.display_name[i]},
         {"parent", model.parent[i] - 1},
         {"joint", model.joint_name[i]},
         {"joint_type", core::to_string(model.joint_type[i])},
         {"X_PJ", {{"p", vec3(model.X_PJ[i].p)}, {"R", quat(core::Quaternion(model.X_PJ[i].R))}}},
         {"axis", vec3(model.axis[i])},
         {"limits", limits_json(model, i)},
         {"range", range_json(model, i)},
         {"shapes", shapes_json(model, i)}});
  }
  // height of the neutral figure: its vertical extent over the link origins
  std::vector<core::Transform> X_W(model.njoints);
  for (int i = 1; i < model.njoints; ++i) {
    X_W[i] = X_W[model.parent[i]] * model.X_PJ[i];
    lowest = i == 1 ? X_W[i].p.y() : std::min(lowest, X_W[i].p.y());
    highest = i == 1 ? X_W[i].p.y() : std::max(highest, X_W[i].p.y());
  }
  return {{"name", name}, {"links", links}, {"height", highest - lowest}, {"skinned", skinned}};
}

json state_json(const animator::Session& s, const std::string& session_id) {
  const core::Model& m = s.model();
  const core::Data& data = s.kinematics();
  json links = json::array();
  for (int i = 1; i < m.njoints; ++i) {
    links.push_back({{"name", m.link_name[i]},
                     {"p", vec3(data.X_W[i].p)},
                     {"R", quat(core::Quaternion(data.X_W[i].R))}});
  }
  json pins = json::array();
  for (const animator::Pin& p : s.pins()) {
    pins.push_back({{"link", m.link_name[p.link]},
                    {"mode", ik::to_string(p.mode)},
                    {"point", vec3(p.p_LinkPoint)},
                    {"target", vec3(p.target_W)},
                    {"rotation", quat(p.target_R_W)}});
  }
  json keys = json::array();
  for (const animator::Keyframe& k : s.keys().keys()) {
    keys.push_back({{"time", k.time}, {"interpolation", animator::to_string(k.interpolation)}});
  }
  json clip = nullptr;
  if (const core::Clip* c = s.clip()) {
    clip = {{"frames", c->size()}, {"frame_time", c->frame_time}, {"duration", c->duration()}};
  }
  json markers = nullptr;
  if (const animator::ClipMarkers* mk = s.clip_markers()) {
    markers = {{"count", mk->set.size()},
               {"frames", mk->measured.frames},
               {"rate", mk->measured.rate_hz},
               {"revision", mk->revision}};
  }
  json layers = json::array();
  for (const auto& layer : s.layers()) {
    layers.push_back({{"name", layer->name},
                      {"first_frame", layer->first_frame},
                      {"last_frame", layer->last_frame()},
                      {"weight", layer->weight},
                      {"muted", layer->muted},
                      {"falloff", layer->falloff}});
  }
  const animator::Playback& pb = s.playback();
  return {{"protocol", kProtocolVersion},
          {"session", session_id},
          {"q", std::vector<double>(s.q().data(), s.q().data() + s.q().size())},
          {"links", links},
          {"pins", pins},
          {"keys", keys},
          {"clip", clip},
          {"markers", markers},
          {"layers", layers},
          {"playback",
           {{"time", pb.time},
            {"playing", pb.playing},
            {"speed", pb.speed},
            {"loop", pb.loop},
            {"loop_start", pb.loop_start},
            {"loop_end", pb.loop_end},
            {"duration", s.duration()}}},
          {"recording", s.recording()},
          {"settings", animator::settings_to_json(s.solver_settings())},
          {"scene", animator::scene_to_json(s.scene())},
          {"falloff", s.edit_falloff()},
          {"undo",
           {{"can_undo", s.history().can_undo()},
            {"can_redo", s.history().can_redo()},
            {"labels", s.history().undo_labels()}}}};
}

json snapshot_json(const animator::Session& s, const std::string& session_id) {
  json j = state_json(s, session_id);
  j["character"] = character_json(s.model(), s.character(), s.skin() != nullptr);
  // a character read from BVH: the unit its file was read in
  if (s.bvh_source()) j["character"]["unit"] = io::bvh_unit_name(s.bvh_source()->scale);
  return j;
}

json report_json(const ik::Report& r) {
  double drag_error = 0, pin_position = 0, pin_orientation = 0;
  for (const ik::TaskReport& t : r.tasks) {
    const std::string_view kind = t.kind;
    if (kind == "drag") drag_error = std::max(drag_error, t.position_error);
    if (kind == "pin") {
      pin_position = std::max(pin_position, t.position_error);
      pin_orientation = std::max(pin_orientation, t.orientation_error);
    }
  }
  return {{"type", "report"},
          {"microseconds", r.microseconds},
          {"drag_error", drag_error},
          {"pin_position_error", pin_position},
          {"pin_orientation_error", pin_orientation},
          {"joint_speed", r.max_joint_speed},
          {"limit_violation", r.limit_violation},
          {"top_rank", r.top_rank}};
}

std::string ack_message(const json& id, const std::string& request) {
  return json{{"type", "ack"}, {"id", id}, {"request", request}}.dump();
}

std::string error_message(const json& id, const std::string& message, const std::string& code) {
  json j{{"type", "error"}, {"message", message}};
  if (!id.is_null()) j["id"] = id;
  if (!code.empty()) j["code"] = code;
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

json physics_json(const animator::PhysicsMeasures& m) {
  json polygon = json::array();
  for (const core::Vector3& p : m.support_polygon) polygon.push_back(vec3(p));
  json contacts = json::array();
  for (const animator::ContactArrow& c : m.contacts) {
    contacts.push_back({{"point", vec3(c.point)}, {"force", vec3(c.force)}});
  }
  json stage_us = json::object();
  for (int e = 0; e < sim::kEffectCount; ++e) {
    stage_us[sim::to_string(sim::kAllEffects[e])] = m.effect_us[e];
  }
  return {{"com", vec3(m.com)},         {"cop", m.cop ? vec3(*m.cop) : json(nullptr)},
          {"support_polygon", polygon}, {"contacts", contacts},
          {"balanced", m.balanced},     {"fallen", m.fallen},
          {"stage_us", stage_us},       {"total_us", m.total_us}};
}

std::string encode_pose_frame(const animator::Session& s,
                              std::uint32_t frame_id,
                              std::uint32_t last_seq) {
  const core::Model& m = s.model();
  const core::Data& data = s.kinematics();
  const int n = m.nlinks();
  std::string b(kPoseHeaderBytes + kPoseBytesPerLink * static_cast<size_t>(n), '\0');
  put_u32(b, 0, kPoseMagic);
  put_u16(b, 4, static_cast<std::uint16_t>(kProtocolVersion));
  put_u16(b, 6, static_cast<std::uint16_t>(n));
  put_u32(b, 8, frame_id);
  put_u32(b, kPoseSeqOffset, last_seq);
  const double time = s.playback().time;
  std::memcpy(b.data() + 16, &time, 8);
  const core::Vector3 root = n > 0 ? data.X_W[1].p : core::Vector3::Zero();
  for (int k = 0; k < 3; ++k) put_f32(b, 24 + 4 * static_cast<size_t>(k), root[k]);
  size_t at = kPoseHeaderBytes;
  for (int i = 1; i <= n; ++i) {
    const core::Quaternion world(data.X_W[i].R);
    // the joint's own rotation: the link in its parent, with the joint placement taken out
    const core::Quaternion own(core::Matrix3(m.X_PJ[i].R.transpose() * data.X_P[i].R));
    const double values[11] = {
        data.X_W[i].p.x(), data.X_W[i].p.y(), data.X_W[i].p.z(), world.w(), world.x(), world.y(),
        world.z(),         own.w(),           own.x(),           own.y(),   own.z()};
    for (double v : values) {
      put_f32(b, at, v);
      at += 4;
    }
  }
  if (const animator::PhysicsSession* physics = s.physics()) {
    b += json{{"physics", physics_json(physics->measures())}}.dump();
  }
  return b;
}

void set_pose_frame_seq(std::string& frame, std::uint32_t last_seq) {
  if (frame.size() >= kPoseHeaderBytes) put_u32(frame, kPoseSeqOffset, last_seq);
}

}  // namespace server
