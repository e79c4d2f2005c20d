// drag_move → pose latency of the server on loopback, and its memory with a client that stops
// reading. A timing program (not Google Benchmark: the figures are percentiles over concurrent
// clients). The server runs in this process on ephemeral ports; each client drags the right hand
// of its own human48 session at 60 Hz and measures the time from sending drag_move seq N to
// receiving the first pose frame whose "last applied seq" is N.
//
//   server_bench [--seconds S] [--sessions N,N,...]   (default: 5 s; 1 and 50 sessions)
//   server_bench --stages [--seconds S]   (one session's latency by stage, stage_run below)
//
// With --mixed it runs the server under mixed load instead (bench/server_load_mixed.hpp):
//
//   server_bench --mixed [--seconds S] [--sessions N] [--mixed-clients K] [--max-rss-mib M]
//                [--max-live-sessions L]
//                (default: 60 s, 50 sessions, 4 other clients, no memory bound, the server's
//                default live-session limit)
//
// and exits 1 when a request failed or the peak resident memory exceeded M MiB.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "bench/server_bench_clients.hpp"
#include "bench/server_load_mixed.hpp"
#include "server/server.hpp"
#include "tests/server/ws_test_client.hpp"

namespace {

using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

using server_bench::create_session;
using server_bench::drag_client;
using server_bench::percentile;
using server_bench::resident_mib;
using server_bench::SessionRef;

void latency_run(server::Server& srv, int sessions, double seconds) {
  std::vector<SessionRef> list;
  for (int k = 0; k < sessions; ++k) list.push_back(create_session(srv.http_port()));
  std::vector<std::vector<double>> latencies(static_cast<size_t>(sessions));
  std::atomic<int> failures{0};
  std::vector<std::thread> clients;
  for (int k = 0; k < sessions; ++k) {
    clients.emplace_back([&, k] { drag_client(srv, list[k], seconds, latencies[k], failures); });
  }
  for (auto& t : clients) t.join();
  std::vector<double> all;
  for (const auto& l : latencies) all.insert(all.end(), l.begin(), l.end());
  const double rate = all.size() / seconds / sessions;
  std::printf(
      "drag_move -> pose, %2d session(s) at 60 Hz for %.0f s: samples %zu (%.1f Hz per client), "
      "p50 %.3f ms, p99 %.3f ms, max %.3f ms, failed clients %d\n",
      sessions, seconds, all.size(), rate, percentile(all, 50), percentile(all, 99),
      all.empty() ? NAN : *std::max_element(all.begin(), all.end()), failures.load());
}

// Where one session's drag latency goes, by stage: three round trips at 60 Hz on one connection,
// taken in turn, and the solver's own time from the reports (sent every 100 ms):
//   echo:  a second hello, answered with an error by the I/O thread (socket and WebSocket only);
//   actor: a pause, acknowledged by the session's actor (adds the hand-off to a pool worker and
//          back to the I/O thread);
//   drag:  drag_move until the pose that applied it (the solve and the pose frame; a cheap
//          sample is solved on the I/O thread, without the hand-off, SessionActor::post).
void stage_run(server::Server& srv, double seconds) {
  const SessionRef s = create_session(srv.http_port());
  const std::string origin = "http://127.0.0.1:" + std::to_string(srv.http_port());
  server_test::WsClient ws(srv.ws_port(), "/ws?session=" + s.id + "&token=" + s.token, origin);
  ws.send({{"type", "hello"}, {"protocol", 1}});
  const std::array<double, 3> start = server_bench::hand_position(ws.read_until("snapshot"));
  ws.send({{"type", "drag_begin"}, {"link", "r_hand"}, {"target", start}});
  std::vector<double> echo, actor, drag, solve;
  const auto note_report = [&](const nlohmann::json& j) {
    if (j.value("type", "") == "report") solve.push_back(j.at("microseconds").get<double>() / 1e3);
  };
  // reads until the text message of `type` answering request `id`, noting reports on the way
  const auto await_reply = [&](const char* type, int id) {
    for (;;) {
      const auto m = ws.read();
      if (!m.text) continue;
      const nlohmann::json j = m.json();
      note_report(j);
      if (j.value("type", "") == type && j.value("id", -1) == id) return;
    }
  };
  const auto t_end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(seconds));
  auto next = Clock::now();
  std::uint32_t seq = 0;
  for (int tick = 0; Clock::now() < t_end; ++tick) {
    std::this_thread::sleep_until(next);
    next += std::chrono::microseconds(16667);
    const int id = 1000 + tick;
    const auto sent = Clock::now();
    if (tick % 3 == 0) {
      ws.send({{"type", "hello"}, {"protocol", 1}, {"id", id}});
      await_reply("error", id);
      echo.push_back(std::chrono::duration<double, std::milli>(Clock::now() - sent).count());
    } else if (tick % 3 == 1) {
      ws.send({{"type", "pause"}, {"id", id}});
      await_reply("ack", id);
      actor.push_back(std::chrono::duration<double, std::milli>(Clock::now() - sent).count());
    } else {
      ++seq;
      ws.send(server_bench::circle_drag_move(start, seq, 40.0));  // every 3rd tick: a 2 s circle
      for (;;) {
        const auto m = ws.read();
        if (m.text) {
          note_report(m.json());
          continue;
        }
        if (server_test::decode_pose(m.data).last_seq >= seq) break;
      }
      drag.push_back(std::chrono::duration<double, std::milli>(Clock::now() - sent).count());
    }
    if (Clock::now() > next) next = Clock::now();
  }
  ws.send({{"type", "drag_end"}});
  ws.close();
  const auto row = [](const char* what, const std::vector<double>& v) {
    std::printf("  %-44s samples %4zu, p50 %.3f ms, p90 %.3f ms, p99 %.3f ms\n", what, v.size(),
                percentile(v, 50), percentile(v, 90), percentile(v, 99));
  };
  std::printf("stages of one session's round trips at 60 Hz for %.0f s:\n", seconds);
  row("echo (I/O thread only)", echo);
  row("actor (I/O -> pool worker -> I/O)", actor);
  row("drag_move -> pose (solve, pose)", drag);
  row("solve, as the server's reports time it", solve);
  // which path the drag samples took (SessionActor::post): solved on the I/O thread that read
  // them, or handed to a pool worker; and how many waited for kMinTickInterval
  const auto actor_ref = srv.registry().find(s.id, s.token).actor;
  if (actor_ref) {
    const server::ActorStats st = actor_ref->stats();
    std::printf(
        "  drag samples: %llu received, %llu solved on the I/O thread, %llu ticks deferred; "
        "last tick %lld us\n",
        static_cast<unsigned long long>(st.drag_samples_received),
        static_cast<unsigned long long>(st.steps_on_posting_thread),
        static_cast<unsigned long long>(st.sample_ticks_deferred),
        static_cast<long long>(st.last_tick_cost.count()));
  }
}

// A client that subscribes and then reads nothing for `stall` seconds while another client drags
// the same session at 60 Hz: the server keeps one pending pose for it, so memory stays flat.
void stalled_reader_run(server::Server& srv, double stall) {
  const SessionRef s = create_session(srv.http_port());
  const std::string origin = "http://127.0.0.1:" + std::to_string(srv.http_port());
  server_test::WsClient stalled(srv.ws_port(), "/ws?session=" + s.id + "&token=" + s.token, origin);
  stalled.send({{"type", "hello"}, {"protocol", 1}});
  stalled.read_until("snapshot");
  const double before = resident_mib();
  double peak = before;
  std::atomic<bool> done{false};
  std::thread sampler([&] {
    while (!done) {
      peak = std::max(peak, resident_mib());
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  });
  std::vector<double> latencies;
  std::atomic<int> failures{0};
  drag_client(srv, s, stall, latencies, failures);
  done = true;
  sampler.join();
  // the stalled client now reads: it gets what was pending, not a backlog of frames
  int frames = 0;
  const auto drain_end = Clock::now() + std::chrono::milliseconds(500);
  try {
    while (Clock::now() < drain_end) {
      if (!stalled.read(std::chrono::milliseconds(500)).text) ++frames;
    }
  } catch (const std::exception&) {
  }
  std::printf(
      "stalled reader for %.0f s while dragging at 60 Hz (%zu drag samples): resident %.1f MiB "
      "before, "
      "peak %.1f MiB (+%.1f MiB); on resuming it received %d pose frames in 0.5 s; dragging client "
      "p99 "
      "%.3f ms\n",
      stall, latencies.size(), before, peak, peak - before, frames, percentile(latencies, 99));
}

}  // namespace

constexpr const char* kUsage =
    "usage: server_bench [--seconds S] [--sessions N,N,...]\n"
    "       server_bench --stages [--seconds S]\n"
    "       server_bench --mixed [--seconds S] [--sessions N] [--mixed-clients K] "
    "[--max-rss-mib M] [--max-live-sessions L]\n";

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  double seconds = 5;
  std::vector<int> session_counts{1, 50};
  bool mixed = false, stages = false, seconds_given = false, sessions_given = false;
  server_bench::MixedLoadOptions mixed_options;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string flag = argv[i];
      if (flag == "--mixed") {
        mixed = true;
        continue;
      }
      if (flag == "--stages") {
        stages = true;
        continue;
      }
      if (i + 1 >= argc) throw std::invalid_argument(flag);
      const std::string value = argv[++i];
      if (flag == "--seconds") {
        seconds = std::stod(value);
        seconds_given = true;
      } else if (flag == "--sessions") {
        session_counts.clear();
        for (size_t at = 0; at < value.size();) {
          const size_t comma = std::min(value.find(',', at), value.size());
          session_counts.push_back(std::stoi(value.substr(at, comma - at)));
          at = comma + 1;
        }
        sessions_given = true;
      } else if (flag == "--mixed-clients") {
        mixed_options.clients = std::stoi(value);
      } else if (flag == "--max-rss-mib") {
        mixed_options.max_rss_mib = std::stod(value);
      } else if (flag == "--max-live-sessions") {
        mixed_options.max_live_sessions = std::stoul(value);
      } else {
        throw std::invalid_argument(flag);
      }
    }
    if (mixed && sessions_given && session_counts.size() != 1) throw std::invalid_argument("");
  } catch (const std::exception&) {
    std::cerr << kUsage;
    return 2;
  }
  if (mixed) {
    // the mixed load: its own server, over a data folder (bench/server_load_mixed.hpp)
    if (seconds_given) mixed_options.seconds = seconds;
    if (sessions_given) mixed_options.sessions = session_counts.front();
    return server_bench::run_mixed_load(mixed_options);
  }
  const fs::path web =
      fs::temp_directory_path() / ("pindrag-server-bench-" + std::to_string(::getpid()));
  fs::create_directories(web);
  std::ofstream(web / "index.html") << "<!doctype html>";
  server::ServerOptions options;
  options.port = 0;
  options.ws_port = 0;
  options.web_root = web.string();   // sessions in memory: the benchmark measures the live path
  options.max_live_sessions = 4096;  // ... which then holds every session it creates
  server::Server srv(options);
  srv.start();
  std::printf("cores: %u\n", std::thread::hardware_concurrency());
  if (stages) {
    stage_run(srv, seconds);
  } else {
    for (int n : session_counts) latency_run(srv, n, seconds);
    stalled_reader_run(srv, 10);
  }
  srv.stop();
  fs::remove_all(web);
  return 0;
}
