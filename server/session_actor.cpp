#include "server/session_actor.hpp"

#include <algorithm>
#include <iostream>
#include <utility>

#include "animator/session_file.hpp"
#include "server/apply_message.hpp"

namespace server {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

namespace {

// what the client hears about a change that could not be saved (the path stays in the log)
std::string not_saved(const animator::SessionWriteError& e) {
  return "not saved (" + std::generic_category().message(e.error()) + "), so not applied";
}

// set while post() runs a step on its caller's thread (SessionActor::kInlineTickBudget)
thread_local bool t_posting_thread_steps = false;

// How much of its time a posting thread may spend in the steps it runs itself: the allowance
// refills at SessionActor::kInlineShare of wall time up to kInlineBurst, and each step run here
// spends its wall time. One session's drag costs well under 1 % of the I/O thread; with many
// sessions dragging at once the allowance runs out and their samples go to the pool's workers, so
// the I/O thread keeps reading and writing for everyone else.
constexpr Clock::duration kInlineBurst = std::chrono::milliseconds(2);
struct InlineAllowance {
  Clock::time_point refilled{};
  Clock::duration left = kInlineBurst;
};
thread_local InlineAllowance t_inline_allowance;

bool inline_allowance_left(Clock::time_point now) {
  auto& a = t_inline_allowance;
  const auto refill =
      std::chrono::duration_cast<Clock::duration>((now - a.refilled) * SessionActor::kInlineShare);
  a.left = std::min(kInlineBurst, a.left + refill);
  a.refilled = now;
  return a.left > Clock::duration::zero();
}

}  // namespace

SessionActor::SessionActor(std::string id,
                           std::unique_ptr<animator::Session> session,
                           std::unique_ptr<SessionJournal> journal,
                           std::shared_ptr<ActorPool> pool)
    : id_(std::move(id)),
      session_(std::move(session)),
      model_(session_->model_ptr()),
      journal_(std::move(journal)),
      pool_(std::move(pool)) {
  start();
}

SessionActor::SessionActor(std::string id,
                           std::unique_ptr<animator::Session> session,
                           const std::string& save_path,
                           std::shared_ptr<ActorPool> pool)
    : id_(std::move(id)),
      session_(std::move(session)),
      model_(session_->model_ptr()),
      journal_(save_path.empty() ? nullptr : SessionJournal::start(save_path, *session_)),
      pool_(std::move(pool)) {
  start();
}

SessionActor::~SessionActor() { stop(); }

void SessionActor::start() {
  last_tick_ = Clock::now();
  if (!session_->needs_tick()) return;  // the first step runs when something is posted
  std::lock_guard lock(mutex_);
  pool_->wake_at(this, last_tick_ + kTickPeriod);
}

void SessionActor::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;  // nothing more is accepted, and no step asks for another
  }
  pool_->remove(this);        // waits for a step in progress
  step();                     // whatever was posted before stop() runs now
  if (was_moving_) settle();  // keep the final state
}

ActorStats SessionActor::stats() const {
  std::lock_guard lock(mutex_);
  ActorStats out = stats_;
  if (journal_) out.snapshots = journal_->snapshots();
  return out;
}

void SessionActor::set_inline_tick_budget(std::chrono::microseconds budget) {
  std::lock_guard lock(mutex_);
  inline_tick_budget_ = budget;
}

void SessionActor::subscribe(std::uint64_t connection,
                             std::shared_ptr<SessionSubscriber> subscriber) {
  Item item;
  item.kind = Item::Kind::kSubscribe;
  item.connection = connection;
  item.subscriber = std::move(subscriber);
  enqueue(std::move(item));
}

void SessionActor::unsubscribe(std::uint64_t connection) {
  Item item;
  item.kind = Item::Kind::kUnsubscribe;
  item.connection = connection;
  enqueue(std::move(item));
}

void SessionActor::post(std::uint64_t connection, ClientRequest request) {
  if (const auto* move = std::get_if<DragMove>(&request.message)) {
    {
      std::lock_guard lock(mutex_);
      ++stats_.drag_samples_received;
      if (stopping_) return;
      if (mailbox_ && mailbox_->connection != connection) {
        // another connection's sample is not superseded by this one: keep it in order
        Item flushed;
        flushed.kind = Item::Kind::kDrag;
        flushed.drag = std::move(*mailbox_);
        queue_.push_back(std::move(flushed));
        mailbox_.reset();
      }
      if (!mailbox_) mailbox_ = DragSample{connection, {}, {}};
      mailbox_->move = *move;
      if (!request.id.is_null()) mailbox_->ack_ids.push_back(std::move(request.id));
      // while a tick waits for kMinTickInterval, samples gather in the mailbox until it is due
      if (tick_deferred_) return;
      const bool cheap = stats_.ticks > 0 && stats_.last_tick_cost <= inline_tick_budget_;
      if (!queue_.empty() || !cheap || !inline_allowance_left(Clock::now())) {
        pool_->wake(this);
        return;
      }
    }
    // a cheap sample with nothing before it: solving it here saves waking a worker, and the
    // worker waking this thread again for the pose
    const auto started = Clock::now();
    t_posting_thread_steps = true;
    const bool ran = pool_->run_here_if_idle(this);
    t_posting_thread_steps = false;
    t_inline_allowance.left -= Clock::now() - started;
    if (!ran) pool_->wake(this);  // a worker has it: make sure it sees this sample
    return;
  }
  Item item;
  item.kind = Item::Kind::kMessage;
  item.connection = connection;
  item.request = std::move(request);
  enqueue(std::move(item));
}

bool SessionActor::enqueue_call(
    std::function<void(animator::Session&, const std::function<void()>& save)> f, bool edit) {
  Item item;
  item.kind = Item::Kind::kCall;
  item.call = std::move(f);
  item.edit = edit;
  return enqueue(std::move(item));
}

bool SessionActor::enqueue(Item item) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return false;
    if (mailbox_) {
      // a command after drag samples: the newest sample is applied first (edits never overtake)
      Item flushed;
      flushed.kind = Item::Kind::kDrag;
      flushed.drag = std::move(*mailbox_);
      queue_.push_back(std::move(flushed));
      mailbox_.reset();
    }
    queue_.push_back(std::move(item));
    pool_->wake(this);  // under the lock: a stopped actor is never woken again
  }
  return true;
}

void SessionActor::step() {
  std::deque<Item> batch;
  std::optional<DragSample> sample;
  {
    std::lock_guard lock(mutex_);
    if (t_posting_thread_steps && !queue_.empty()) {
      // a command arrived since post() chose to step here: commands (and the journal writes
      // they may need) run on a worker, so this step leaves everything to it
      pool_->wake(this);
      return;
    }
    if (t_posting_thread_steps) ++stats_.steps_on_posting_thread;
    batch.swap(queue_);
    sample.swap(mailbox_);
    tick_deferred_ = false;
  }
  bool new_drag_sample = false;
  for (Item& item : batch) {
    if (item.kind == Item::Kind::kDrag) {
      new_drag_sample = apply_drag(item.drag) || new_drag_sample;
    } else {
      process(item);
    }
  }
  if (sample) new_drag_sample = apply_drag(*sample) || new_drag_sample;

  // a new drag sample is solved at once unless the last sample's tick was under kMinTickInterval
  // ago. A periodic tick does not count: samples at 60 Hz drift against the ticks of kTickPeriod,
  // and one arriving just after such a tick would wait up to kMinTickInterval for nothing.
  const auto now = Clock::now();
  const bool moving = session_->needs_tick();
  tick_owed_ = moving && (tick_owed_ || new_drag_sample);
  const bool sample_due = tick_owed_ && now - last_sample_tick_ >= kMinTickInterval;
  if (moving && (sample_due || now - last_tick_ >= kTickPeriod)) {
    if (tick_owed_) last_sample_tick_ = now;
    tick();
    tick_owed_ = false;
  }
  if (pose_dirty_) broadcast_pose();
  if (was_moving_ && !session_->needs_tick()) {
    if (t_posting_thread_steps) {
      // a worker records where the figure came to rest (this thread writes no files)
      std::lock_guard lock(mutex_);
      if (!stopping_) pool_->wake(this);
      return;
    }
    // the readouts show the state the figure came to rest in, not the last one sent in motion
    if (held_report_) broadcast_text(*std::exchange(held_report_, std::nullopt));
    settle();  // keep where the figure came to rest
  }
  was_moving_ = session_->needs_tick();
  if (journal_) journal_->snapshot_if_due(/*settled=*/false);

  std::optional<Clock::time_point> next_tick;
  if (was_moving_)
    next_tick = tick_owed_ ? last_sample_tick_ + kMinTickInterval : last_tick_ + kTickPeriod;
  std::lock_guard lock(mutex_);
  if (stopping_) return;
  tick_deferred_ = was_moving_ && tick_owed_;
  if (tick_deferred_) ++stats_.sample_ticks_deferred;
  pool_->wake_at(this, next_tick);
}

bool SessionActor::apply_drag(DragSample& sample) {
  {
    std::lock_guard lock(mutex_);
    ++stats_.drag_samples_applied;
  }
  const auto last = last_seq_.find(sample.connection);
  if (last != last_seq_.end() && sample.move.seq <= last->second) {
    const std::string message = "drag_move.seq: must increase per connection (last applied " +
                                std::to_string(last->second) + ", got " +
                                std::to_string(sample.move.seq) + ")";
    for (const auto& id : sample.ack_ids) send_to(sample.connection, error_message(id, message));
    return false;
  }
  try {
    apply(*session_, sample.move);
  } catch (const std::exception& e) {
    for (const auto& id : sample.ack_ids) send_to(sample.connection, error_message(id, e.what()));
    if (sample.ack_ids.empty()) send_to(sample.connection, error_message(nullptr, e.what()));
    return false;
  }
  last_seq_[sample.connection] = sample.move.seq;
  for (const auto& id : sample.ack_ids)
    send_to(sample.connection, ack_message(id, DragMove::kType));
  return true;
}

void SessionActor::process(Item& item) {
  switch (item.kind) {
    case Item::Kind::kSubscribe: {
      nlohmann::json snapshot = snapshot_json(*session_, id_);
      snapshot["type"] = "snapshot";
      item.subscriber->send_text(
          snapshot.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
      const std::uint32_t seq = last_seq_.count(item.connection) ? last_seq_[item.connection] : 0;
      item.subscriber->send_pose(encode_pose_frame(*session_, frame_id_, seq));
      subscribers_[item.connection] = std::move(item.subscriber);
      break;
    }
    case Item::Kind::kUnsubscribe:
      subscribers_.erase(item.connection);
      last_seq_.erase(item.connection);
      if (drag_owner_ == item.connection) {
        // the client left mid-gesture: end its drag as a drag_end would (one undo entry)
        drag_owner_.reset();
        if (session_->dragging()) {
          std::optional<animator::Session::Checkpoint> checkpoint;
          if (journal_) checkpoint = session_->checkpoint();
          session_->drag_end();
          try {
            if (checkpoint) save_edit(json{{"type", "drag_end"}}, std::move(*checkpoint));
          } catch (const animator::SessionWriteError&) {
            // taken back; nobody is left to tell but the log (save_edit wrote it)
          }
          after_edit();
        }
      }
      break;
    case Item::Kind::kCall: {
      const bool edit = item.edit;
      std::optional<animator::Session::Checkpoint> checkpoint;
      if (edit && journal_) checkpoint = session_->checkpoint();
      item.call(*session_, [&] {
        if (checkpoint) save_edit(json{{"type", "call"}}, std::move(*checkpoint));
      });
      if (edit) after_edit();
      break;
    }
    case Item::Kind::kMessage:
      apply_request(item.connection, item.request);
      break;
    case Item::Kind::kDrag:
      apply_drag(item.drag);
      break;
  }
}

void SessionActor::apply_request(std::uint64_t connection, const ClientRequest& request) {
  std::optional<animator::Session::Checkpoint> checkpoint;
  if (journal_) checkpoint = session_->checkpoint();
  try {
    apply(*session_, request.message);
  } catch (const std::exception& e) {
    send_to(connection, error_message(request.id, e.what()));
    return;
  }
  // durable before acknowledged
  if (checkpoint) {
    try {
      save_edit(to_json(request.message), std::move(*checkpoint));
    } catch (const animator::SessionWriteError& e) {
      drag_owner_.reset();  // taking the edit back ended any drag
      send_to(
          connection,
          error_message(request.id, std::string(message_type(request.message)) + ": " + e.what(),
                        kNotSaved));
      after_edit();  // every page draws the state again, without the edit
      return;
    }
  }
  if (std::holds_alternative<DragBegin>(request.message)) drag_owner_ = connection;
  if (std::holds_alternative<DragEnd>(request.message)) drag_owner_.reset();
  if (!request.id.is_null())
    send_to(connection, ack_message(request.id, message_type(request.message)));
  // a drag shows in the pose frames; anything else may change what `state` carries
  if (!std::holds_alternative<DragBegin>(request.message)) after_edit();
}

void SessionActor::after_edit() {
  pose_dirty_ = true;
  json state = state_json(*session_, id_);
  state["type"] = "state";
  broadcast_text(state.dump(-1, ' ', false, json::error_handler_t::replace));
}

// Records what changed since the last record; when that fails, returns the session to what the
// disk holds with the undo history of `checkpoint` and throws SessionWriteError for the client.
void SessionActor::save_edit(const json& op, animator::Session::Checkpoint checkpoint) {
  try {
    if (!journal_->record(*session_, op)) return;
    std::lock_guard lock(mutex_);
    ++stats_.saves;
  } catch (const animator::SessionWriteError& e) {
    std::cerr << "pindrag serve: session " << id_ << ": " << op.value("type", "edit")
              << " not saved, taken back: " << e.what() << "\n";
    session_->roll_back(journal_->document(), journal_->playback(), std::move(checkpoint));
    {
      std::lock_guard lock(mutex_);
      ++stats_.save_failures;
    }
    throw animator::SessionWriteError(e.error(), not_saved(e));
  }
}

// The figure came to rest: its pose (and the playback time) are recorded, which nobody waits
// for; a failure is announced to every connection and the next edit's record carries it.
void SessionActor::settle() {
  if (!journal_) return;
  try {
    if (journal_->record(*session_, json{{"type", "settle"}})) {
      std::lock_guard lock(mutex_);
      ++stats_.saves;
    }
  } catch (const animator::SessionWriteError& e) {
    std::cerr << "pindrag serve: session " << id_ << ": the settled pose not saved: " << e.what()
              << "\n";
    const std::string why = std::generic_category().message(e.error());
    broadcast_text(error_message(
        nullptr, "session: the pose the figure came to rest in is not saved (" + why + ")",
        kNotSaved));
    std::lock_guard lock(mutex_);
    ++stats_.save_failures;
    return;
  }
  journal_->snapshot_if_due(/*settled=*/true);
}

void SessionActor::tick() {
  const auto now = Clock::now();
  const double dt = std::clamp(std::chrono::duration<double>(now - last_tick_).count(), 0.0, 0.1);
  last_tick_ = now;
  const auto result = session_->tick(dt);
  {
    std::lock_guard lock(mutex_);
    ++stats_.ticks;
    stats_.last_tick_cost =
        std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - now);
  }
  if (result.pose_changed) pose_dirty_ = true;
  if (result.committed) after_edit();
  if (!result.report) return;
  if (now - last_report_ >= std::chrono::milliseconds(100)) {
    last_report_ = now;
    held_report_.reset();
    broadcast_text(report_json(*result.report).dump());
  } else {
    held_report_ = report_json(*result.report).dump();  // sent when the figure comes to rest
  }
}

void SessionActor::broadcast_pose() {
  pose_dirty_ = false;
  ++frame_id_;
  std::string frame = encode_pose_frame(*session_, frame_id_, 0);
  for (auto& [connection, subscriber] : subscribers_) {
    const auto seq = last_seq_.find(connection);
    set_pose_frame_seq(frame, seq == last_seq_.end() ? 0 : seq->second);
    subscriber->send_pose(frame);
  }
  std::lock_guard lock(mutex_);
  ++stats_.pose_frames;
}

void SessionActor::broadcast_text(const std::string& text) {
  for (auto& entry : subscribers_) entry.second->send_text(text);
}

void SessionActor::send_to(std::uint64_t connection, std::string text) {
  const auto it = subscribers_.find(connection);
  if (it != subscribers_.end()) it->second->send_text(std::move(text));
}

}  // namespace server
