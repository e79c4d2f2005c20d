#include "bench/server_bench_clients.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <thread>

#include "tests/server/ws_test_client.hpp"

#include <httplib.h>  // after the server's headers (Eigen): see server/http_routes.hpp

namespace server_bench {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr auto kFramePeriod = std::chrono::microseconds(16667);  // 60 Hz

}  // namespace

std::array<double, 3> hand_position(const json& snapshot) {
  for (const json& l : snapshot.at("links")) {
    if (l.at("name") == "r_hand") return {l.at("p")[0], l.at("p")[1], l.at("p")[2]};
  }
  throw std::runtime_error("no r_hand");
}

SessionRef create_session(int port) {
  httplib::Client c("127.0.0.1", port);
  const auto res = c.Post("/api/sessions", R"({"character": "human48"})", "application/json");
  if (!res || res->status != 201) throw std::runtime_error("cannot create a session");
  const json j = json::parse(res->body);
  return {j.at("id"), j.at("token")};
}

nlohmann::json circle_drag_move(const std::array<double, 3>& start,
                                std::uint32_t seq,
                                double frames_per_circle) {
  const double phase = 2 * M_PI * seq / frames_per_circle;
  return {{"type", "drag_move"},
          {"seq", seq},
          {"target",
           {start[0] + 0.1 * std::cos(phase) - 0.1, start[1] + 0.1 * std::sin(phase), start[2]}}};
}

void drag_client(const server::Server& srv,
                 const SessionRef& s,
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
      const auto sent = Clock::now();
      ws.send(circle_drag_move(start, seq, 120.0));  // a 2 s circle
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

double resident_mib() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  statm >> pages_total >> pages_resident;
  return static_cast<double>(pages_resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) /
         (1024.0 * 1024.0);
}

}  // namespace server_bench
