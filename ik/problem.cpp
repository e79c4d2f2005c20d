#include "ik/problem.hpp"

#include <algorithm>

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

}  // namespace ik
