// An IK problem: tasks by priority level. The drag goes on top and is solved exactly; pins,
// reference angles and range rows go on the lower level, in the null space of the top
// (Yamane ch. 8). Joint limits and spherical ranges come from the model and are added by the
// solver while violated (ik/limits.hpp).
#pragma once

#include <variant>
#include <vector>

#include "ik/task.hpp"

namespace ik {

enum class Priority { kTop, kLower };
constexpr Priority kTop = Priority::kTop;
constexpr Priority kLower = Priority::kLower;

using Task = std::variant<DragTask, PinTask, JointReferenceTask>;

class Problem {
 public:
  struct Entry {
    int id = 0;
    Priority priority = kLower;
    Task task;
  };

  /// Adds a task and returns its id (stable until removed).
  int add(const Task& task, Priority priority);
  int add(const DragTask& t) { return add(Task(t), kTop); }
  int add(const PinTask& t) { return add(Task(t), kLower); }
  int add(const JointReferenceTask& t) { return add(Task(t), kLower); }
  bool remove(int id);
  void clear() { entries_.clear(); }

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

  /// Whether the solver adds joint-limit and spherical-range rows (on the lower level).
  bool enforce_ranges = true;

 private:
  std::vector<Entry> entries_;
  int next_id_ = 1;
};

}  // namespace ik
