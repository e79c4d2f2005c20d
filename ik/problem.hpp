// An IK problem: tasks by priority. The solver has three levels, each solved in the null space
// of the levels above it (Yamane ch. 8):
//   1. the drag (tasks added with kTop): solved exactly;
//   2. joint ranges: rows the solver adds itself for joints at or beyond their ranges
//      (ik/limits.hpp; from the model, never added here);
//   3. pins and joint references (tasks added with kLower): solved with the SR inverse.
// A problem holds the tasks of levels 1 and 3; Priority says which of the two a task is on.
#pragma once

#include <variant>
#include <vector>

#include "ik/task.hpp"

namespace ik {

/// kTop: level 1, with the drag; kLower: level 3, with the pins and references.
enum class Priority { kTop, kLower };
constexpr Priority kTop = Priority::kTop;
constexpr Priority kLower = Priority::kLower;

using Task = std::variant<LinkTask, JointReferenceTask>;

class Problem {
 public:
  struct Entry {
    int id = 0;
    Priority priority = kLower;
    Task task;
  };

  /// Adds a task and returns its id (stable until removed).
  int add(const Task& task, Priority priority);
  /// A drag goes on top (level 1), a pin on the lower level (3).
  int add(const LinkTask& t) { return add(Task(t), t.role == kDrag ? kTop : kLower); }
  int add(const JointReferenceTask& t) { return add(Task(t), kLower); }
  bool remove(int id);
  void clear() {
    entries_.clear();
    locked_joints.clear();
  }

  /// The task with this id, or nullptr (also when it holds another kind).
  template <typename T>
  T* get(int id) {
    for (Entry& e : entries_) {
      if (e.id == id) return std::get_if<T>(&e.task);
    }
    return nullptr;
  }
  const std::vector<Entry>& entries() const { return entries_; }
  std::vector<Entry>& entries() { return entries_; }

  /// True when a drag or a pin is present: the IK stage has something to do.
  bool active() const;

  /// Whether the solver adds joint-limit and spherical-range rows (level 2).
  bool enforce_ranges = true;

  /// Joints the solver holds still: their coordinates get no velocity on any level (as a joint
  /// of ik_weight 0). Empty in the problems callers build; ik::PinHold locks joints a correction
  /// would carry out of their ranges.
  std::vector<int> locked_joints;

 private:
  std::vector<Entry> entries_;
  int next_id_ = 1;
};

/// Adds a reference on every moving joint below the root (revolute, prismatic, spherical) toward
/// its value in q, with the default gain and weight: the posture q as a preference.
void add_joint_references(const core::Model& model, const Eigen::VectorXd& q, Problem& problem);

}  // namespace ik
