#include "cli/dynamics_state.hpp"

#include "cli/json_fields.hpp"
#include "core/aba.hpp"
#include "core/configuration.hpp"
#include "core/crba.hpp"
#include "core/rnea.hpp"

namespace cli {

namespace {

using io::JsonField;
using io::JsonFields;
using nlohmann::json;

// array of exactly n entries, else an error naming the field and the expected form
void array_of(JsonFields& f, const JsonField& j, std::size_t n, const char* form) {
  if (!j->is_array() || j->size() != n) {
    f.fail(j, std::string("expected ") + form + ", got " +
                  (j->is_array() ? "an array of " + std::to_string(j->size()) : f.kind(*j)));
  }
}

// one joint's velocity-like entry (v, a or tau) into out[iv ..]
void read_velocity(
    JsonFields& f, const core::Model& m, int i, const JsonField& j, Eigen::VectorXd& out) {
  const int iv = m.idx_v[i];
  switch (m.joint_type[i]) {
    case core::JointType::kRevolute:
    case core::JointType::kPrismatic:
      out[iv] = f.number(j);
      break;
    case core::JointType::kSpherical:
      array_of(f, j, 3, "3 numbers [x, y, z] (child frame)");
      for (std::size_t k = 0; k < 3; ++k) out[iv + k] = f.number(j[k]);
      break;
    case core::JointType::kFree:
      array_of(f, j, 6, "6 numbers [ωx, ωy, ωz, vx, vy, vz] (child frame)");
      for (std::size_t k = 0; k < 6; ++k) out[iv + k] = f.number(j[k]);
      break;
    case core::JointType::kFixed:
      break;
  }
}

// one joint's configuration entry into q[iq ..]
void read_configuration(
    JsonFields& f, const core::Model& m, int i, const JsonField& j, Eigen::VectorXd& q) {
  const int iq = m.idx_q[i];
  switch (m.joint_type[i]) {
    case core::JointType::kRevolute:
    case core::JointType::kPrismatic:
      q[iq] = f.number(j);
      break;
    case core::JointType::kSpherical:
      core::set_quaternion_at(q, iq, f.quaternion(j));
      break;
    case core::JointType::kFree: {
      array_of(f, j, 7, "7 numbers [x, y, z, w, qx, qy, qz]");
      for (std::size_t k = 0; k < 3; ++k) q[iq + k] = f.number(j[k]);
      // the quaternion part keeps its index in the field name (/q/root/3 … /q/root/6)
      for (std::size_t k = 3; k < 7; ++k) f.number(j[k]);
      const json wxyz = json::array({(*j)[3], (*j)[4], (*j)[5], (*j)[6]});
      core::set_quaternion_at(q, iq + 3,
                              f.quaternion(JsonField(&wxyz, j.pointer() + " (quaternion part)")));
      break;
    }
    case core::JointType::kFixed:
      break;
  }
}

// {"joint": value, ...} for key `key` of the state, each joint through `read`
template <typename Read>
void read_section(
    JsonFields& f, const core::Model& m, const JsonField& state, const char* key, Read&& read) {
  const JsonField section = state[key];
  if (!section) return;
  if (!section->is_object()) f.fail(section, "expected an object keyed by joint name");
  for (const auto& [name, value] : section->items()) {
    const JsonField joint = section[name];
    const int i = m.joint_index(name);
    if (i < 1) f.fail(joint, "unknown joint " + io::in_quotes(name) + " in '" + m.name + "'");
    if (m.joint_type[i] == core::JointType::kFixed) {
      f.fail(joint, "joint " + io::in_quotes(name) + " is fixed and has no coordinates");
    }
    read(i, joint);
  }
}

NamedState read_state(JsonFields& f, const core::Model& m, const JsonField& state) {
  if (!state->is_object()) f.fail(state, "expected an object with q, v, a and tau");
  f.warn_unknown_keys(state, {"q", "v", "a", "tau"});
  NamedState s;
  s.q = core::neutral_configuration(m);
  s.v = s.a = s.tau = Eigen::VectorXd::Zero(m.nv);
  read_section(f, m, state, "q",
               [&](int i, const JsonField& j) { read_configuration(f, m, i, j, s.q); });
  read_section(f, m, state, "v",
               [&](int i, const JsonField& j) { read_velocity(f, m, i, j, s.v); });
  read_section(f, m, state, "a",
               [&](int i, const JsonField& j) { read_velocity(f, m, i, j, s.a); });
  read_section(f, m, state, "tau",
               [&](int i, const JsonField& j) { read_velocity(f, m, i, j, s.tau); });
  return s;
}

// a velocity-space vector as {"joint": number or array}
json by_joint(const core::Model& m, const Eigen::VectorXd& x) {
  json out = json::object();
  for (int i = 1; i < m.njoints; ++i) {
    const int n = core::joint_nv(m.joint_type[i]);
    if (n == 0) continue;
    if (n == 1) {
      out[m.joint_name[i]] = x[m.idx_v[i]];
    } else {
      out[m.joint_name[i]] = std::vector<double>(x.data() + m.idx_v[i], x.data() + m.idx_v[i] + n);
    }
  }
  return out;
}

}  // namespace

NamedState read_named_state(const core::Model& m, const json& state) {
  JsonFields f = request_fields();
  return io::rethrow_as<RequestError>([&] { return read_state(f, m, JsonField(state)); });
}

std::vector<std::string> velocity_names(const core::Model& m) {
  std::vector<std::string> names(m.nv);
  for (int i = 1; i < m.njoints; ++i) {
    const int n = core::joint_nv(m.joint_type[i]);
    for (int k = 0; k < n; ++k) {
      names[m.idx_v[i] + k] =
          n == 1 ? m.joint_name[i] : m.joint_name[i] + "[" + std::to_string(k) + "]";
    }
  }
  return names;
}

json run_dynamics(const core::Model& m, const json& state) {
  const NamedState s = read_named_state(m, state);
  core::Data d(m);
  json out;
  out["character"] = m.name;
  out["fixed_base"] = m.joint_type[1] == core::JointType::kFixed;
  out["nq"] = m.nq;
  out["nv"] = m.nv;
  out["order"] = velocity_names(m);
  out["tau"] = by_joint(m, core::rnea(m, d, s.q, s.v, s.a));
  out["a"] = by_joint(m, core::aba(m, d, s.q, s.v, s.tau));
  const Eigen::MatrixXd& M = core::crba(m, d, s.q);
  json rows = json::array();
  for (int r = 0; r < m.nv; ++r) {
    rows.push_back(std::vector<double>(m.nv));
    for (int c = 0; c < m.nv; ++c) rows.back()[c] = M(r, c);
  }
  out["M"] = rows;
  out["bias"] = by_joint(m, core::bias_forces(m, d, s.q, s.v));
  return out;
}

}  // namespace cli
