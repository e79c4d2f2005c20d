// Undo and redo as commands (STYLE.md §7): one entry per gesture, pin change, key edit or clip
// edit; entries of one gesture merge into one.
//
// An entry stores what its edit changed, not copies of the document: the pose, pins, settings,
// scene and falloff before and after (small), the clip and the layer list before and after as
// shared pointers (clips and layers are immutable and shared with the document), and of the keys
// only the ones removed and added (a key edit on a track of thousands of keys holds one or two).
// Redo restores exactly the state undo left.
//
// Memory is accounted in bytes: what an entry holds that the document does not (its poses, pins,
// changed keys, and the clip and layers its edit replaced). Above the byte budget the oldest
// entries are dropped; the newest entry is always kept, so the last edit can be undone.
//
// A checkpoint of the history is cheap (entries are shared; only the one that merging and
// amending change in place is copied), so an edit that could not be saved is taken back exactly.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "animator/document.hpp"

namespace animator {

class Session;

class Command {
 public:
  virtual ~Command() = default;
  virtual void apply(Session& s) = 0;
  virtual void revert(Session& s) = 0;
  /// Absorbs `next` (same gesture) into this command; false when they stay separate.
  virtual bool merge_with(const Command& next) = 0;
  virtual const std::string& label() const = 0;
  /// Bytes this command keeps alive beyond the session's document.
  virtual std::size_t bytes() const = 0;
  virtual std::unique_ptr<Command> clone() const = 0;
};

/// A change of the session's document from `before` to `after`.
class DocumentChange final : public Command {
 public:
  DocumentChange(const Document& before, const Document& after, std::string label, int gesture);
  void apply(Session& s) override;
  void revert(Session& s) override;
  bool merge_with(const Command& next) override;
  const std::string& label() const override { return label_; }
  std::size_t bytes() const override { return bytes_; }
  std::unique_ptr<Command> clone() const override;
  int gesture() const { return gesture_; }
  /// The state this change ends in (after settling, see History::amend). The keys must be
  /// those it already ends with (settling moves the figure, never a key).
  void set_after(const Document& after);

 private:
  // everything of a document but its keys
  struct Side {
    Eigen::VectorXd q;
    std::vector<Pin> pins;
    std::shared_ptr<const core::Clip> clip;
    std::shared_ptr<const ClipMarkers> markers;
    LayerStack layers;
    ik::SolverSettings settings;
    sim::Scene scene;
    double edit_falloff = kDefaultEditFalloff;
    explicit Side(const Document& d);
    void assign_to(Document& d) const;
  };
  void go_to(Session& s, const Side& side, bool forward) const;
  void count_bytes();

  Side before_, after_;
  KeyChange keys_;
  std::string label_;
  int gesture_;  // entries with the same gesture id (> 0) merge
  std::size_t bytes_ = 0;
};

class History {
 public:
  /// At most this many entries are kept; the oldest are dropped first.
  static constexpr size_t kCapacity = 2000;
  /// Default byte budget (Limits::max_undo_bytes).
  static constexpr size_t kDefaultByteBudget = std::size_t{64} << 20;

  /// Records a command that has already been applied (merging with the last one if it can).
  void record(std::unique_ptr<Command> command);
  /// Updates the end state of the newest entry if it is the change with this gesture id and
  /// nothing was undone since: the figure settling after an edit belongs to that edit.
  bool amend(int gesture, const Document& after);
  bool undo(Session& s);
  bool redo(Session& s);
  bool can_undo() const { return cursor_ > 0; }
  bool can_redo() const { return cursor_ < entries_.size(); }
  size_t size() const { return entries_.size(); }
  /// Labels of the entries that undo would revert, newest last.
  std::vector<std::string> undo_labels() const;
  void clear() {
    entries_.clear();
    cursor_ = 0;
    bytes_ = 0;
  }

  /// Bytes the entries hold (Command::bytes, summed).
  size_t bytes() const { return bytes_; }
  size_t byte_budget() const { return byte_budget_; }
  /// Sets the budget and drops the oldest entries until the rest fit (keeping the newest).
  void set_byte_budget(size_t bytes);
  /// Entries dropped so far to stay within the budget and the capacity.
  size_t dropped() const { return dropped_; }

  /// The history as it is now, to go back to with restore().
  struct Checkpoint {
    std::deque<std::shared_ptr<Command>> entries;
    // a copy of entries[cursor - 1], the one entry that record() and amend() change in place
    std::shared_ptr<Command> current;
    size_t cursor = 0, bytes = 0, dropped = 0;
  };
  Checkpoint checkpoint() const;
  void restore(Checkpoint checkpoint);

 private:
  void trim();

  std::deque<std::shared_ptr<Command>> entries_;
  size_t cursor_ = 0;  // entries_[0, cursor_) are applied
  size_t bytes_ = 0;
  size_t byte_budget_ = kDefaultByteBudget;
  size_t dropped_ = 0;
};

}  // namespace animator
