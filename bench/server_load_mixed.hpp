// The server under mixed load: N clients drag their own sessions at 60 Hz over the WebSocket
// while K other clients, in rounds, create a session, open it in a page and leave again
// (reconnect), export BVH and glTF, fetch a thumbnail and delete the oldest sessions they created.
// The server runs in this process over a temporary data folder, so beyond its live-session limit
// idle sessions leave memory and come back from disk. Reported: the drag_move → pose
// round trip, each operation's count, refusals (503 with Retry-After, the documented "busy") and
// errors (any other non-2xx answer, a failed connection or an unexpected body), and the process's
// resident memory and threads sampled every 100 ms.
#pragma once

#include <cstddef>

namespace server_bench {

struct MixedLoadOptions {
  double seconds = 60;
  int sessions = 50;                  // dragging clients, one session each
  int clients = 4;                    // the other clients
  double max_rss_mib = 0;             // > 0: a higher peak of resident memory fails the run
  std::size_t max_live_sessions = 0;  // the server's --max-live-sessions (0: its default)
};

/// Runs the load and prints its figures. Returns 0 when nothing failed and the peak resident
/// memory stayed within max_rss_mib, else 1.
int run_mixed_load(const MixedLoadOptions& options);

}  // namespace server_bench
