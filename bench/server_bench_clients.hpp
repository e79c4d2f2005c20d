// The clients of the server timing programs (server_bench): creating a session over HTTP, a
// client dragging its session's right hand at 60 Hz over the WebSocket and timing each drag_move
// to the pose frame that applies it, percentiles, and the process's resident memory.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "server/server.hpp"

namespace server_bench {

struct SessionRef {
  std::string id, token;
};

/// A human48 session. @throws std::runtime_error unless the server answers 201
SessionRef create_session(int port);

/// The right hand's position in a snapshot (world, m). @throws std::runtime_error without one
std::array<double, 3> hand_position(const nlohmann::json& snapshot);

/// drag_move `seq` of a drag around a circle of 10 cm radius through `start` (world, m), once
/// around every `frames_per_circle` moves.
nlohmann::json circle_drag_move(const std::array<double, 3>& start,
                                std::uint32_t seq,
                                double frames_per_circle);

/// Drags the right hand of `s` on a 2 s circle at 60 Hz for `seconds`, appending each drag_move →
/// pose round trip (ms) to `latencies`; a client that fails prints why and increments `failures`.
void drag_client(const server::Server& srv,
                 const SessionRef& s,
                 double seconds,
                 std::vector<double>& latencies,
                 std::atomic<int>& failures);

/// The p-th percentile (nearest rank) of `v`; NaN when it is empty.
double percentile(std::vector<double> v, double p);

/// This process's resident memory (/proc/self/statm), MiB.
double resident_mib();

}  // namespace server_bench
