#include "animator/history.hpp"

#include <algorithm>

#include "animator/session.hpp"

namespace animator {

namespace {

// what a heap block costs beyond its bytes (glibc's malloc header, rounded)
constexpr std::size_t kBlockOverhead = 16;

std::size_t vector_bytes(const Eigen::VectorXd& v) {
  return static_cast<std::size_t>(v.size()) * sizeof(double) + kBlockOverhead;
}

std::size_t clip_bytes(const core::Clip& c) {
  std::size_t n = c.frames.capacity() * sizeof(Eigen::VectorXd) + kBlockOverhead;
  for (const Eigen::VectorXd& f : c.frames) n += vector_bytes(f);
  return n;
}

std::size_t layer_bytes(const EditLayer& l) {
  std::size_t n = sizeof(EditLayer) + l.name.capacity() +
                  l.displacement.capacity() * sizeof(Eigen::VectorXd) + kBlockOverhead;
  for (const Eigen::VectorXd& d : l.displacement) n += vector_bytes(d);
  return n;
}

std::size_t markers_bytes(const ClipMarkers& m) {
  std::size_t n = sizeof(ClipMarkers) + m.set.markers.capacity() * sizeof(ik::Marker) +
                  m.measured.positions.capacity() * sizeof(core::Vector3) +
                  m.measured.present.capacity() + 3 * kBlockOverhead;
  for (const ik::Marker& marker : m.set.markers) n += marker.name.capacity();
  return n;
}

bool holds(const LayerStack& layers, const std::shared_ptr<const EditLayer>& layer) {
  return std::find(layers.begin(), layers.end(), layer) != layers.end();
}

}  // namespace

DocumentChange::Side::Side(const Document& d)
    : q(d.q),
      pins(d.pins),
      clip(d.clip),
      markers(d.markers),
      layers(d.layers),
      settings(d.settings),
      scene(d.scene),
      edit_falloff(d.edit_falloff) {}

void DocumentChange::Side::assign_to(Document& d) const {
  d.q = q;
  d.pins = pins;
  d.clip = clip;
  d.markers = markers;
  d.layers = layers;
  d.settings = settings;
  d.scene = scene;
  d.edit_falloff = edit_falloff;
}

DocumentChange::DocumentChange(const Document& before,
                               const Document& after,
                               std::string label,
                               int gesture)
    : before_(before),
      after_(after),
      keys_(diff_keys(before.keys, after.keys)),
      label_(std::move(label)),
      gesture_(gesture) {
  count_bytes();
}

void DocumentChange::go_to(Session& s, const Side& side, bool forward) const {
  // the keys now are this change's end (or start) keys: every key edit is an entry of its own
  Document d = s.document();
  side.assign_to(d);
  d.keys.apply(keys_, forward);
  s.apply_document(d);
}

void DocumentChange::apply(Session& s) { go_to(s, after_, true); }
void DocumentChange::revert(Session& s) { go_to(s, before_, false); }

void DocumentChange::set_after(const Document& after) {
  after_ = Side(after);
  count_bytes();
}

std::unique_ptr<Command> DocumentChange::clone() const {
  return std::make_unique<DocumentChange>(*this);
}

bool DocumentChange::merge_with(const Command& next) {
  const auto* n = dynamic_cast<const DocumentChange*>(&next);
  if (!n || gesture_ <= 0 || n->gesture_ != gesture_) return false;
  after_ = n->after_;
  keys_ = compose(keys_, n->keys_);
  count_bytes();
  return true;
}

void DocumentChange::count_bytes() {
  std::size_t n = sizeof(*this) + label_.capacity() + keys_.bytes();
  for (const Side* side : {&before_, &after_}) {
    n += vector_bytes(side->q) + side->pins.capacity() * sizeof(Pin) +
         side->layers.capacity() * sizeof(LayerStack::value_type);
  }
  // what the edit replaced lives on in this entry only; what it made is the document's
  if (before_.clip && before_.clip != after_.clip) n += clip_bytes(*before_.clip);
  if (before_.markers && before_.markers != after_.markers) n += markers_bytes(*before_.markers);
  for (const auto& layer : before_.layers) {
    if (!holds(after_.layers, layer)) n += layer_bytes(*layer);
  }
  bytes_ = n;
}

void History::record(std::unique_ptr<Command> command) {
  // a new edit drops the redo branch
  while (entries_.size() > cursor_) {
    bytes_ -= entries_.back()->bytes();
    entries_.pop_back();
  }
  if (!entries_.empty()) {
    const std::size_t old = entries_.back()->bytes();
    if (entries_.back()->merge_with(*command)) {
      bytes_ = bytes_ - old + entries_.back()->bytes();
      trim();
      return;
    }
  }
  bytes_ += command->bytes();
  entries_.push_back(std::move(command));
  cursor_ = entries_.size();
  trim();
}

void History::trim() {
  auto over = [this] { return bytes_ > byte_budget_ || entries_.size() > kCapacity; };
  // the oldest applied entries first, keeping the newest applied one
  while (over() && cursor_ > 1) {
    bytes_ -= entries_.front()->bytes();
    entries_.pop_front();
    --cursor_;
    ++dropped_;
  }
  // then the redo entries furthest from now (only when everything was undone)
  while (over() && entries_.size() > std::max<std::size_t>(cursor_, 1)) {
    bytes_ -= entries_.back()->bytes();
    entries_.pop_back();
    ++dropped_;
  }
}

void History::set_byte_budget(size_t bytes) {
  byte_budget_ = bytes;
  trim();
}

bool History::amend(int gesture, const Document& after) {
  if (entries_.empty() || cursor_ != entries_.size()) return false;
  auto* change = dynamic_cast<DocumentChange*>(entries_.back().get());
  if (!change || change->gesture() != gesture) return false;
  const std::size_t old = change->bytes();
  change->set_after(after);
  bytes_ = bytes_ - old + change->bytes();
  trim();
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
  return Checkpoint{entries_, cursor_ > 0 ? entries_[cursor_ - 1]->clone() : nullptr, cursor_,
                    bytes_, dropped_};
}

void History::restore(Checkpoint checkpoint) {
  entries_ = std::move(checkpoint.entries);
  cursor_ = checkpoint.cursor;
  bytes_ = checkpoint.bytes;
  dropped_ = checkpoint.dropped;
  if (cursor_ > 0) entries_[cursor_ - 1] = std::move(checkpoint.current);
}

std::vector<std::string> History::undo_labels() const {
  std::vector<std::string> out;
  for (size_t i = 0; i < cursor_; ++i) out.push_back(entries_[i]->label());
  return out;
}

}  // namespace animator
