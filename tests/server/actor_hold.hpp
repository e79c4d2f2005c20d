// Holds a session actor busy in one of its steps until release(), so that what is posted
// meanwhile waits in its queue and mailbox: the tests of coalescing and ordering use it.
#pragma once

#include <future>
#include <memory>
#include <thread>

#include "server/session_actor.hpp"

namespace server_test {

class ActorHold {
 public:
  /// Returns once the actor is inside the holding step.
  explicit ActorHold(server::SessionActor& actor) {
    auto entered = std::make_shared<std::promise<void>>();
    auto entered_future = entered->get_future();
    thread_ = std::thread([&actor, entered, released = release_.get_future().share()] {
      actor.call([&](animator::Session&) {
        entered->set_value();
        released.wait();
      });
    });
    entered_future.wait();
  }
  ~ActorHold() { release(); }
  ActorHold(const ActorHold&) = delete;
  ActorHold& operator=(const ActorHold&) = delete;

  /// Lets the actor go on, and waits until the holding step has returned.
  void release() {
    if (!thread_.joinable()) return;
    release_.set_value();
    thread_.join();
  }

 private:
  std::promise<void> release_;
  std::thread thread_;
};

}  // namespace server_test
