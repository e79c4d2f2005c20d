// Undo and redo as commands (STYLE.md §7): one entry per gesture, pin change, key edit or clip
// edit. A command stores the document before and after, so redo restores exactly the state undo
// left; entries of one gesture merge into one. A checkpoint of the history is cheap (entries are
// shared; only the one that merging and amending change in place is copied), so an edit
// that could not be saved can be taken back exactly.
#pragma once

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
  virtual std::unique_ptr<Command> clone() const = 0;
};

/// A change of the session's document from `before` to `after`.
class DocumentChange final : public Command {
 public:
  DocumentChange(Document before, Document after, std::string label, int gesture);
  void apply(Session& s) override;
  void revert(Session& s) override;
  bool merge_with(const Command& next) override;
  const std::string& label() const override { return label_; }
  std::unique_ptr<Command> clone() const override;
  int gesture() const { return gesture_; }
  /// The state this change ends in (after settling, see History::amend).
  void set_after(const Document& after) { after_ = std::make_shared<const Document>(after); }

 private:
  // shared and never changed in place, so a clone (History::checkpoint) copies two pointers
  std::shared_ptr<const Document> before_, after_;
  std::string label_;
  int gesture_;  // entries with the same gesture id (> 0) merge
};

class History {
 public:
  /// At most this many entries are kept; the oldest are dropped first.
  static constexpr size_t kCapacity = 2000;

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
  }

  /// The history as it is now, to go back to with restore().
  struct Checkpoint {
    std::vector<std::shared_ptr<Command>> entries;
    // a copy of entries[cursor - 1], the one entry that record() and amend() change in place
    std::shared_ptr<Command> current;
    size_t cursor = 0;
  };
  Checkpoint checkpoint() const;
  void restore(Checkpoint checkpoint);

 private:
  std::vector<std::shared_ptr<Command>> entries_;
  size_t cursor_ = 0;  // entries_[0, cursor_) are applied
};

}  // namespace animator
