// drag_move → pose latency of the server on loopback, and its memory with a client that stops
// reading. A timing program (not Google Benchmark: the figures are percentiles over concurrent
// clients). The server runs in this process on ephemeral ports; each client drags the right hand
// of its own human48 session at 60 Hz and measures the time from sending drag_move seq N to
// receiving the first pose frame whose "last applied seq" is N.
//
//   server_bench [--seconds S] [--sessions N,N,...]   (default: 5 s; 1 and 50 sessions)
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
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

#include "server/server.hpp"
#include "tests/server/ws_test_client.hpp"

#include <httplib.h>  // after the server's headers (Eigen): see server/http_routes.hpp

namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

constexpr auto kFramePeriod = std::chrono::microseconds(16667);  // 60 Hz

struct Session {
  std::string id, token;
};

Session create_session(int port) {
  httplib::Client c("127.0.0.1", port);
  const auto res = c.Post("/api/sessions", R"({"character": "human48"})", "application/json");
  if (!res || res->status != 201) throw std::runtime_error("cannot create a session");
  const json j = json::parse(res->body);
  return {j.at("id"), j.at("token")};
}

double resident_mib() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  statm >> pages_total >> pages_resident;
  return static_cast<double>(pages_resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) /
         (1024.0 * 1024.0);
}

std::array<double, 3> hand_position(const json& snapshot) {
  for (const json& l : snapshot.at("links")) {
    if (l.at("name") == "r_hand") return {l.at("p")[0], l.at("p")[1], l.at("p")[2]};
  }
  throw std::runtime_error("no r_hand");
}

// One client dragging for `seconds`; appends its latencies (ms).
void drag_client(const server::Server& srv,
                 const Session& s,
                 double seconds,
                 std::vector<double>& latencies,
                 std::atomic<int>& failures) {
  try {
    const std::string origin = "http://127.0.0.1:" + std::to_string(srv.http_port());
    server_test::WsClient ws(srv.ws_port(), "/ws?session=" + s.id + "&token=" + s.token, origin);
    ws.send({{"type", "hello"}, {"protocol", 1}});
    const auto start = hand_position(ws.read_until("snapshot"));
    ws.send({{"type", "drag_begin"}, {"link", "r_hand"}, {"target", start}});
    const auto t_end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                          std::chrono::duration<double>(seconds));
    auto next = Clock::now();
    for (std::uint32_t seq = 1; Clock::now() < t_end; ++seq) {
      std::this_thread::sleep_until(next);
      next += kFramePeriod;
      const double phase = 2 * M_PI * seq / 120.0;  // a 2 s circle of 10 cm radius
      const auto sent = Clock::now();
      ws.send(
          {{"type", "drag_move"},
           {"seq", seq},
           {"target",
            {start[0] + 0.1 * std::cos(phase) - 0.1, start[1] + 0.1 * std::sin(phase), start[2]}}});
      for (;;) {
        const auto m = ws.read();
        if (m.text) continue;
        if (server_test::decode_pose(m.data).last_seq >= seq) break;
      }
      latencies.push_back(std::chrono::duration<double, std::milli>(Clock::now() - sent).count());
      if (Clock::now() > next) next = Clock::now();  // late: do not send a catch-up burst
    }
    ws.send({{"type", "drag_end"}});
    ws.close();
  } catch (const std::exception& e) {
    std::cerr << "client failed: " << e.what() << "\n";
    ++failures;
  }
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(std::ceil(p / 100.0 * v.size())) - 1);
  return v[k];
}

void latency_run(server::Server& srv, int sessions, double seconds) {
  std::vector<Session> list;
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

// A client that subscribes and then reads nothing for `stall` seconds while another client drags
// the same session at 60 Hz: the server keeps one pending pose for it, so memory stays flat.
void stalled_reader_run(server::Server& srv, double stall) {
  const Session s = create_session(srv.http_port());
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

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  double seconds = 5;
  std::vector<int> session_counts{1, 50};
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--seconds") {
      seconds = std::stod(argv[i + 1]);
    } else if (flag == "--sessions") {
      session_counts.clear();
      std::string list = argv[i + 1];
      for (size_t at = 0; at < list.size();) {
        const size_t comma = std::min(list.find(',', at), list.size());
        session_counts.push_back(std::stoi(list.substr(at, comma - at)));
        at = comma + 1;
      }
    } else {
      std::cerr << "usage: server_bench [--seconds S] [--sessions N,N,...]\n";
      return 2;
    }
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
  for (int n : session_counts) latency_run(srv, n, seconds);
  stalled_reader_run(srv, 10);
  srv.stop();
  fs::remove_all(web);
  return 0;
}
