#include "server/session_actor.hpp"

#include <algorithm>
#include <iostream>

#include "animator/session_file.hpp"
#include "server/apply_message.hpp"

namespace server {

using Clock = std::chrono::steady_clock;

SessionActor::SessionActor(std::string id,
                           std::unique_ptr<animator::Session> session,
                           std::string save_path)
    : id_(std::move(id)),
      session_(std::move(session)),
      model_(session_->model_ptr()),
      save_path_(std::move(save_path)),
      thread_([this] { run(); }) {}

SessionActor::~SessionActor() { stop(); }

void SessionActor::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  if (thread_.joinable() && thread_.get_id() != std::this_thread::get_id()) thread_.join();
}

ActorStats SessionActor::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
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
    }
    wake_.notify_one();
    return;
  }
  Item item;
  item.kind = Item::Kind::kMessage;
  item.connection = connection;
  item.request = std::move(request);
  enqueue(std::move(item));
}

bool SessionActor::enqueue_call(std::function<void(animator::Session&)> f, bool edit) {
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
  }
  wake_.notify_one();
  return true;
}

void SessionActor::run() {
  last_tick_ = Clock::now();
  for (;;) {
    std::deque<Item> batch;
    std::optional<DragSample> sample;
    {
      std::unique_lock lock(mutex_);
      auto ready = [&] { return stopping_ || !queue_.empty() || mailbox_.has_value(); };
      if (session_->needs_tick()) {
        wake_.wait_until(lock, last_tick_ + kTickPeriod, ready);
      } else {
        wake_.wait(lock, ready);
      }
      batch.swap(queue_);
      sample.swap(mailbox_);
      if (stopping_ && batch.empty() && !sample) break;
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

    const auto now = Clock::now();
    const bool moving = session_->needs_tick();
    if (moving && ((new_drag_sample && now - last_tick_ >= kMinTickInterval) ||
                   now - last_tick_ >= kTickPeriod)) {
      tick();
    } else if (moving && new_drag_sample) {
      // too soon after the last tick: come back when the interval has passed
      std::unique_lock lock(mutex_);
      wake_.wait_until(lock, last_tick_ + kMinTickInterval,
                       [&] { return stopping_ || !queue_.empty(); });
      lock.unlock();
      if (session_->needs_tick()) tick();
    }
    if (pose_dirty_) broadcast_pose();
    if (was_moving_ && !session_->needs_tick()) save();  // the figure settled: keep where it ended
    was_moving_ = session_->needs_tick();
  }
  // whatever was posted before stop() has run; keep the final state
  if (was_moving_) save();
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
          session_->drag_end();
          after_edit();
        }
      }
      break;
    case Item::Kind::kCall:
      item.call(*session_);
      if (item.edit) after_edit();
      break;
    case Item::Kind::kMessage:
      apply_request(item.connection, item.request);
      break;
    case Item::Kind::kDrag:
      apply_drag(item.drag);
      break;
  }
}

void SessionActor::apply_request(std::uint64_t connection, const ClientRequest& request) {
  try {
    apply(*session_, request.message);
  } catch (const std::exception& e) {
    send_to(connection, error_message(request.id, e.what()));
    return;
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
  nlohmann::json state = state_json(*session_, id_);
  state["type"] = "state";
  broadcast_text(state.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
  save();
}

void SessionActor::tick() {
  const auto now = Clock::now();
  const double dt = std::clamp(std::chrono::duration<double>(now - last_tick_).count(), 0.0, 0.1);
  last_tick_ = now;
  const auto result = session_->tick(dt);
  {
    std::lock_guard lock(mutex_);
    ++stats_.ticks;
  }
  if (result.pose_changed) pose_dirty_ = true;
  if (result.committed) after_edit();
  if (result.report && now - last_report_ >= std::chrono::milliseconds(100)) {
    last_report_ = now;
    broadcast_text(report_json(*result.report).dump());
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

void SessionActor::save() {
  if (save_path_.empty()) return;
  try {
    animator::save_session(*session_, save_path_);
    std::lock_guard lock(mutex_);
    ++stats_.saves;
  } catch (const std::exception& e) {
    std::cerr << "pindrag serve: could not save session " << id_ << ": " << e.what() << "\n";
  }
}

}  // namespace server
