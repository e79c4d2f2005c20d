#include "ik/problem.hpp"

#include <algorithm>

#include "core/configuration.hpp"

namespace ik {

int Problem::add(const Task& task, Priority priority) {
  entries_.push_back({next_id_, priority, task});
  return next_id_++;
}

bool Problem::remove(int id) {
  const auto it =
      std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.id == id; });
  if (it == entries_.end()) return false;
  entries_.erase(it);
  return true;
}

bool Problem::active() const {
  return std::any_of(entries_.begin(), entries_.end(),
                     [](const Entry& e) { return std::holds_alternative<LinkTask>(e.task); });
}

void add_joint_references(const core::Model& model, const Eigen::VectorXd& q, Problem& problem) {
  for (int j = 2; j < model.njoints; ++j) {
    JointReferenceTask r;
    r.joint = j;
    switch (model.joint_type[j]) {
      case core::JointType::kSpherical:
        r.R_ref = core::quaternion_at(q, model.idx_q[j]);
        break;
      case core::JointType::kRevolute:
      case core::JointType::kPrismatic:
        r.q_ref = q[model.idx_q[j]];
        break;
      default:
        continue;  // fixed joints do not move; a free joint below the root is not referenced
    }
    problem.add(r);
  }
}

}  // namespace ik
