#include "cli/dynamics_state.hpp"

#include "cli/json_fields.hpp"
#include "core/aba.hpp"
#include "core/configuration.hpp"
#include "core/crba.hpp"
#include "core/rnea.hpp"

namespace cli {

namespace {

using nlohmann::json;

// array of exactly n entries, else an error naming the field and the expected form
const json& array_of(const json& j, size_t n, const std::string& field, const char* form) {
  if (!j.is_array() || j.size() != n) {
    throw RequestError(
        field + ": expected " + form + ", got " +
        (j.is_array() ? "an array of " + std::to_string(j.size()) : std::string(j.type_name())));
  }
  return j;
}

// one joint's velocity-like entry (v, a or tau) into out[iv ..]
void read_velocity(
    const core::Model& m, int i, const json& j, const std::string& field, Eigen::VectorXd& out) {
  const int iv = m.idx_v[i];
  switch (m.joint_type[i]) {
    case core::JointType::kRevolute:
    case core::JointType::kPrismatic:
      out[iv] = number(j, field);
      break;
    case core::JointType::kSpherical:
      array_of(j, 3, field, "3 numbers [x, y, z] (child frame)");
      for (int k = 0; k < 3; ++k) out[iv + k] = number(j[k], field + "/" + std::to_string(k));
      break;
    case core::JointType::kFree:
      array_of(j, 6, field, "6 numbers [ωx, ωy, ωz, vx, vy, vz] (child frame)");
      for (int k = 0; k < 6; ++k) out[iv + k] = number(j[k], field + "/" + std::to_string(k));
      break;
    case core::JointType::kFixed:
      break;
  }
}

// one joint's configuration entry into q[iq ..]
void read_configuration(
    const core::Model& m, int i, const json& j, const std::string& field, Eigen::VectorXd& q) {
  const int iq = m.idx_q[i];
  switch (m.joint_type[i]) {
    case core::JointType::kRevolute:
    case core::JointType::kPrismatic:
      q[iq] = number(j, field);
      break;
    case core::JointType::kSpherical:
      core::set_quaternion_at(q, iq, quaternion_wxyz(j, field));
      break;
    case core::JointType::kFree: {
      array_of(j, 7, field, "7 numbers [x, y, z, w, qx, qy, qz]");
      for (int k = 0; k < 3; ++k) q[iq + k] = number(j[k], field + "/" + std::to_string(k));
      // the quaternion part keeps its index in the field name (/q/root/3 … /q/root/6)
      for (int k = 3; k < 7; ++k) number(j[k], field + "/" + std::to_string(k));
      const json wxyz = json::array({j[3], j[4], j[5], j[6]});
      core::set_quaternion_at(q, iq + 3, quaternion_wxyz(wxyz, field + " (quaternion part)"));
      break;
    }
    case core::JointType::kFixed:
      break;
  }
}

// {"joint": value, ...} for key `key` of the state, each joint through `read`
template <typename Read>
void read_section(const core::Model& m, const json& state, const char* key, Read&& read) {
  if (!state.contains(key)) return;
  const std::string field = std::string("/") + key;
  const json& section = state[key];
  if (!section.is_object()) throw RequestError(field + ": expected an object keyed by joint name");
  for (const auto& [name, value] : section.items()) {
    const std::string f = field + "/" + name;
    const int i = m.joint_index(name);
    if (i < 1) throw RequestError(f + ": unknown joint '" + name + "' in '" + m.name + "'");
    if (m.joint_type[i] == core::JointType::kFixed) {
      throw RequestError(f + ": joint '" + name + "' is fixed and has no coordinates");
    }
    read(i, value, f);
  }
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
  if (!state.is_object()) throw RequestError("/: expected an object with q, v, a and tau");
  warn_unknown_keys(state, "", {"q", "v", "a", "tau"});
  NamedState s;
  s.q = core::neutral_configuration(m);
  s.v = s.a = s.tau = Eigen::VectorXd::Zero(m.nv);
  read_section(m, state, "q", [&](int i, const json& j, const std::string& f) {
    read_configuration(m, i, j, f, s.q);
  });
  read_section(m, state, "v",
               [&](int i, const json& j, const std::string& f) { read_velocity(m, i, j, f, s.v); });
  read_section(m, state, "a",
               [&](int i, const json& j, const std::string& f) { read_velocity(m, i, j, f, s.a); });
  read_section(m, state, "tau", [&](int i, const json& j, const std::string& f) {
    read_velocity(m, i, j, f, s.tau);
  });
  return s;
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
