#include "animator/history.hpp"

#include "animator/session.hpp"

namespace animator {

DocumentChange::DocumentChange(Document before, Document after, std::string label, int gesture)
    : before_(std::make_shared<const Document>(std::move(before))),
      after_(std::make_shared<const Document>(std::move(after))),
      label_(std::move(label)),
      gesture_(gesture) {}

void DocumentChange::apply(Session& s) { s.apply_document(*after_); }
void DocumentChange::revert(Session& s) { s.apply_document(*before_); }

std::unique_ptr<Command> DocumentChange::clone() const {
  return std::make_unique<DocumentChange>(*this);
}

bool DocumentChange::merge_with(const Command& next) {
  const auto* n = dynamic_cast<const DocumentChange*>(&next);
  if (!n || gesture_ <= 0 || n->gesture_ != gesture_) return false;
  after_ = n->after_;
  return true;
}

void History::record(std::unique_ptr<Command> command) {
  entries_.resize(cursor_);  // a new edit drops the redo branch
  if (!entries_.empty() && entries_.back()->merge_with(*command)) return;
  entries_.push_back(std::move(command));
  if (entries_.size() > kCapacity) entries_.erase(entries_.begin());
  cursor_ = entries_.size();
}

bool History::amend(int gesture, const Document& after) {
  if (entries_.empty() || cursor_ != entries_.size()) return false;
  auto* change = dynamic_cast<DocumentChange*>(entries_.back().get());
  if (!change || change->gesture() != gesture) return false;
  change->set_after(after);
  return true;
}

bool History::undo(Session& s) {
  if (!can_undo()) return false;
  entries_[--cursor_]->revert(s);
  return true;
}

bool History::redo(Session& s) {
  if (!can_redo()) return false;
  entries_[cursor_++]->apply(s);
  return true;
}

History::Checkpoint History::checkpoint() const {
  return Checkpoint{entries_, cursor_ > 0 ? entries_[cursor_ - 1]->clone() : nullptr, cursor_};
}

void History::restore(Checkpoint checkpoint) {
  entries_ = std::move(checkpoint.entries);
  cursor_ = checkpoint.cursor;
  if (cursor_ > 0) entries_[cursor_ - 1] = std::move(checkpoint.current);
}

std::vector<std::string> History::undo_labels() const {
  std::vector<std::string> out;
  for (size_t i = 0; i < cursor_; ++i) out.push_back(entries_[i]->label());
  return out;
}

}  // namespace animator
