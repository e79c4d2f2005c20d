#include "bench/server_load_mixed.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "bench/server_bench_clients.hpp"
#include "server/server.hpp"
#include "tests/server/ws_test_client.hpp"

#include <httplib.h>  // after the server's headers (Eigen): see server/http_routes.hpp

namespace server_bench {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

// what the other clients do, in the order of the report
enum Op { kCreate, kReconnect, kExportBvh, kExportGltf, kThumbnail, kDelete, kOps };
constexpr std::array<const char*, kOps> kOpNames{"create",      "reconnect", "export bvh",
                                                 "export gltf", "thumbnail", "delete"};

constexpr std::size_t kKeepCreated = 3;  // sessions a client keeps of those it created
constexpr auto kRoundPause = std::chrono::milliseconds(100);
constexpr double kKeyTimes[] = {0, 5, 10};  // the animated session's keys: 301 frames at 30 fps
constexpr int kAnimationFrames = 301;
constexpr int kErrorsPrinted = 20;

struct OpStats {
  std::vector<double> ms;  // durations of the successful ones
  int ok = 0, busy = 0, errors = 0;
  double bytes = 0;  // bodies of the successful answers
};
using ClientStats = std::array<OpStats, kOps>;

// Errors are printed as they happen (the first kErrorsPrinted of them).
class ErrorLog {
 public:
  void report(Op op, const std::string& what) {
    std::lock_guard lock(mutex_);
    if (printed_++ < kErrorsPrinted) std::cerr << "error: " << kOpNames[op] << ": " << what << "\n";
  }

 private:
  std::mutex mutex_;
  int printed_ = 0;
};

int thread_count() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("Threads:", 0) == 0) return std::stoi(line.substr(8));
  }
  return 0;
}

// Resident memory and threads of this process, every 100 ms until stop().
class ProcessSampler {
 public:
  ProcessSampler() : start_rss_(resident_mib()), start_threads_(thread_count()) {
    peak_threads_ = start_threads_;
    thread_ = std::thread([this] {
      while (!done_) {
        samples_.push_back({Clock::now(), resident_mib()});
        peak_threads_ = std::max(peak_threads_, thread_count());
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    });
  }
  ~ProcessSampler() { stop(); }
  void stop() {
    done_ = true;
    if (thread_.joinable()) thread_.join();
  }
  double start_rss() const { return start_rss_; }
  int start_threads() const { return start_threads_; }
  // after stop():
  int peak_threads() const { return peak_threads_; }
  /// The highest resident memory sampled in [from, to).
  double peak_rss(Clock::time_point from = Clock::time_point::min(),
                  Clock::time_point to = Clock::time_point::max()) const {
    double peak = 0;
    for (const auto& [at, mib] : samples_) {
      if (at >= from && at < to) peak = std::max(peak, mib);
    }
    return peak;
  }

 private:
  struct Sample {
    Clock::time_point at;
    double mib;
  };
  double start_rss_;
  int start_threads_, peak_threads_;
  std::vector<Sample> samples_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

bool is_bvh(const std::string& body) { return body.rfind("HIERARCHY", 0) == 0; }
bool is_gltf(const std::string& body) {
  const json j = json::parse(body, nullptr, false);
  return j.is_object() && j.contains("asset");
}
bool is_png(const std::string& body) { return body.rfind("\x89PNG", 0) == 0; }

// One of the other clients: rounds of create, reconnect, export, thumbnail and delete until the
// deadline, over the sessions the dragging clients hold and an animated session of its own.
class MixedClient {
 public:
  MixedClient(const server::Server& srv,
              const std::vector<SessionRef>& dragged,
              unsigned seed,
              ErrorLog& log)
      : port_(srv.http_port()),
        ws_port_(srv.ws_port()),
        origin_("http://127.0.0.1:" + std::to_string(srv.http_port())),
        dragged_(dragged),
        rng_(seed),
        log_(log) {}

  void run(Clock::time_point deadline) {
    animated_ = make_animated();
    for (int round = 0; Clock::now() < deadline; ++round) {
      // a new session, opened in a page and left again
      if (const auto s = create()) {
        created_.push_back(*s);
        reconnect(*s);
      }
      // the animated session, which may have left memory meanwhile, opened again
      if (animated_) reconnect(*animated_);
      // exports, alternately of the animation and of a session being dragged
      const bool animation = animated_ && round % 2 == 0;
      const SessionRef& source = animation ? *animated_ : dragged();
      export_as(source, "bvh", kExportBvh, is_bvh);
      export_as(source, "gltf", kExportGltf, is_gltf);
      // a thumbnail: a frame of the animation, or the current pose of a session being dragged
      if (animation) {
        thumbnail(*animated_, "?frame=" + std::to_string(rng_() % kAnimationFrames));
      } else {
        thumbnail(dragged(), "");
      }
      // the live set stays bounded: the oldest created sessions go
      while (created_.size() > kKeepCreated) {
        remove(created_.front());
        created_.pop_front();
      }
      std::this_thread::sleep_for(kRoundPause);
    }
  }

  const ClientStats& stats() const { return stats_; }

 private:
  const SessionRef& dragged() { return dragged_[rng_() % dragged_.size()]; }

  void fail(Op op, const std::string& what) {
    ++stats_[op].errors;
    log_.report(op, what);
  }

  // Sends one request and files its outcome under `op`: a 2xx answer whose body `valid` accepts,
  // a 503 with Retry-After (busy), or an error. Returns the answer when it succeeded.
  std::optional<httplib::Response> request(
      Op op,
      const std::function<httplib::Result(httplib::Client&)>& send,
      const std::function<bool(const std::string&)>& valid) {
    httplib::Client c("127.0.0.1", port_);
    c.set_connection_timeout(10, 0);
    c.set_read_timeout(30, 0);
    const auto t0 = Clock::now();
    const httplib::Result res = send(c);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (!res) {
      fail(op, "no answer (" + httplib::to_string(res.error()) + ")");
      return std::nullopt;
    }
    if (res->status == 503 && res->has_header("Retry-After")) {
      ++stats_[op].busy;
      return std::nullopt;
    }
    if (res->status < 200 || res->status > 299) {
      fail(op, "status " + std::to_string(res->status) + ": " + res->body.substr(0, 300));
      return std::nullopt;
    }
    if (!valid(res->body)) {
      fail(op, "unexpected body: " + res->body.substr(0, 40));
      return std::nullopt;
    }
    ++stats_[op].ok;
    stats_[op].ms.push_back(ms);
    stats_[op].bytes += static_cast<double>(res->body.size());
    return *res;
  }

  std::optional<SessionRef> create() {
    const auto res = request(
        kCreate,
        [this](httplib::Client& c) {
          return c.Post("/api/sessions", {{"Origin", origin_}}, R"({"character": "human48"})",
                        "application/json");
        },
        [](const std::string& body) {
          const json j = json::parse(body, nullptr, false);
          return j.is_object() && j.contains("id") && j.contains("token");
        });
    if (!res) return std::nullopt;
    const json j = json::parse(res->body);
    return SessionRef{j.at("id"), j.at("token")};
  }

  std::unique_ptr<server_test::WsClient> open(const SessionRef& s) {
    auto ws = std::make_unique<server_test::WsClient>(
        ws_port_, "/ws?session=" + s.id + "&token=" + s.token, origin_);
    ws->send({{"type", "hello"}, {"protocol", 1}});
    return ws;
  }

  // opens the session as a page does (hello, snapshot) and closes it again
  void reconnect(const SessionRef& s) {
    const auto t0 = Clock::now();
    try {
      const auto ws = open(s);
      ws->read_until("snapshot");
      ws->close();
    } catch (const std::exception& e) {
      // a refused upgrade answers 503 when every live session is held
      if (std::string(e.what()).rfind("status 503", 0) == 0) {
        ++stats_[kReconnect].busy;
      } else {
        fail(kReconnect, e.what());
      }
      return;
    }
    ++stats_[kReconnect].ok;
    stats_[kReconnect].ms.push_back(
        std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }

  void export_as(const SessionRef& s,
                 const std::string& format,
                 Op op,
                 const std::function<bool(const std::string&)>& valid) {
    request(
        op,
        [&](httplib::Client& c) {
          return c.Get("/api/sessions/" + s.id + "/export?format=" + format,
                       {{"X-Session-Token", s.token}});
        },
        valid);
  }

  void thumbnail(const SessionRef& s, const std::string& query) {
    request(
        kThumbnail,
        [&](httplib::Client& c) {
          return c.Get("/api/sessions/" + s.id + "/thumbnail.png" + query,
                       {{"X-Session-Token", s.token}});
        },
        is_png);
  }

  void remove(const SessionRef& s) {
    request(
        kDelete,
        [&](httplib::Client& c) {
          return c.Delete("/api/sessions/" + s.id,
                          {{"Origin", origin_}, {"X-Session-Token", s.token}});
        },
        [](const std::string&) { return true; });
  }

  // Sends `message` with an id and waits for its ack.
  static void acknowledged(server_test::WsClient& ws, json message, int id) {
    message["id"] = id;
    ws.send(message);
    for (;;) {
      const server_test::WsMessage m = ws.read();
      if (!m.text) continue;
      const json j = m.json();
      if (j.value("id", -1) != id) continue;
      if (j.value("type", "") == "ack") return;
      throw std::runtime_error(message.value("type", "") + ": " + j.dump());
    }
  }

  // A session of this client with an animation to export: a key at each of kKeyTimes, the right
  // hand dragged a little between them.
  std::optional<SessionRef> make_animated() {
    const auto s = create();
    if (!s) return std::nullopt;
    try {
      const auto ws = open(*s);
      const json snapshot = ws->read_until("snapshot");
      json hand;
      for (const json& l : snapshot.at("links")) {
        if (l.at("name") == "r_hand") hand = l.at("p");
      }
      int id = 1;
      std::uint32_t seq = 1;
      for (const double t : kKeyTimes) {
        acknowledged(*ws, {{"type", "key_insert"}, {"time", t}}, id++);
        hand[1] = hand[1].get<double>() + 0.05;
        ws->send({{"type", "drag_begin"}, {"link", "r_hand"}, {"target", hand}});
        ws->send({{"type", "drag_move"}, {"seq", seq++}, {"target", hand}});
        acknowledged(*ws, {{"type", "drag_end"}}, id++);
      }
      ws->close();
    } catch (const std::exception& e) {
      fail(kCreate, std::string("animating a session: ") + e.what());
      return std::nullopt;
    }
    return s;
  }

  int port_, ws_port_;
  std::string origin_;
  const std::vector<SessionRef>& dragged_;
  std::mt19937 rng_;
  ErrorLog& log_;
  std::optional<SessionRef> animated_;
  std::deque<SessionRef> created_;
  ClientStats stats_;
};

void print_drag(const MixedLoadOptions& o,
                const std::vector<std::vector<double>>& latencies,
                int failures) {
  std::vector<double> all;
  for (const auto& l : latencies) all.insert(all.end(), l.begin(), l.end());
  std::printf(
      "drag_move -> pose: samples %zu (%.1f Hz per client), p50 %.3f ms, p99 %.3f ms, max %.3f ms, "
      "failed clients %d\n",
      all.size(), all.size() / o.seconds / o.sessions, percentile(all, 50), percentile(all, 99),
      all.empty() ? NAN : *std::max_element(all.begin(), all.end()), failures);
}

// the operations' table; returns the errors and the busy answers
std::pair<int, int> print_operations(const std::vector<MixedClient>& clients) {
  std::printf("%-12s %7s %7s %9s %7s %9s %9s %9s %9s\n", "operation", "count", "ok", "busy 503",
              "errors", "p50 ms", "p99 ms", "max ms", "mean KiB");
  int errors = 0, busy = 0;
  for (int op = 0; op < kOps; ++op) {
    OpStats sum;
    for (const MixedClient& c : clients) {
      const OpStats& s = c.stats()[op];
      sum.ok += s.ok;
      sum.busy += s.busy;
      sum.errors += s.errors;
      sum.bytes += s.bytes;
      sum.ms.insert(sum.ms.end(), s.ms.begin(), s.ms.end());
    }
    std::printf("%-12s %7d %7d %9d %7d %9.3f %9.3f %9.3f %9.1f\n", kOpNames[op],
                sum.ok + sum.busy + sum.errors, sum.ok, sum.busy, sum.errors,
                percentile(sum.ms, 50), percentile(sum.ms, 99),
                sum.ms.empty() ? NAN : *std::max_element(sum.ms.begin(), sum.ms.end()),
                sum.ok > 0 ? sum.bytes / sum.ok / 1024 : NAN);
    errors += sum.errors;
    busy += sum.busy;
  }
  return {errors, busy};
}

}  // namespace

int run_mixed_load(const MixedLoadOptions& o) {
  const fs::path base =
      fs::temp_directory_path() / ("pindrag-server-load-" + std::to_string(::getpid()));
  fs::remove_all(base);
  fs::create_directories(base / "web");
  std::ofstream(base / "web" / "index.html") << "<!doctype html>";
  server::ServerOptions options;
  options.port = 0;
  options.ws_port = 0;
  options.web_root = (base / "web").string();
  options.data_dir = (base / "data").string();  // stored sessions: idle ones leave memory
  if (o.max_live_sessions > 0) options.max_live_sessions = o.max_live_sessions;
  int status = 0;
  try {
    server::Server srv(options);
    srv.start();
    std::printf(
        "mixed load: %d sessions dragged at 60 Hz and %d other clients for %.0f s; cores %u, "
        "actor threads %zu, live sessions at most %zu\n",
        o.sessions, o.clients, o.seconds, std::thread::hardware_concurrency(),
        srv.registry().actor_threads(), srv.registry().options().max_live);
    ProcessSampler sampler;
    std::vector<SessionRef> dragged;
    for (int k = 0; k < o.sessions; ++k) dragged.push_back(create_session(srv.http_port()));

    ErrorLog log;
    std::vector<MixedClient> mixed;
    mixed.reserve(static_cast<size_t>(o.clients));
    for (int k = 0; k < o.clients; ++k) mixed.emplace_back(srv, dragged, 1000u + k, log);
    // the drag samples' memory is taken before the load, so that what grows during it is the
    // server's and the connections'
    std::vector<std::vector<double>> latencies(dragged.size());
    for (auto& l : latencies) {
      l.assign(static_cast<size_t>(o.seconds * 60 * 1.05) + 60, 0.0);
      l.clear();
    }
    const double loaded_rss = resident_mib();
    std::atomic<int> failures{0};
    const auto length =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.seconds));
    const auto load_start = Clock::now(), deadline = load_start + length;
    std::vector<std::thread> threads;
    for (size_t k = 0; k < dragged.size(); ++k) {
      threads.emplace_back(
          [&, k] { drag_client(srv, dragged[k], o.seconds, latencies[k], failures); });
    }
    for (MixedClient& c : mixed) threads.emplace_back([&c, deadline] { c.run(deadline); });
    for (auto& t : threads) t.join();
    const double end_rss = resident_mib();
    const int end_threads = thread_count();
    sampler.stop();

    print_drag(o, latencies, failures.load());
    const auto [errors, busy] = print_operations(mixed);
    std::printf(
        "errors %d, busy (503 with Retry-After) %d; sessions at the end: %zu stored, %zu live, "
        "%zu WebSocket connections\n",
        errors + failures.load(), busy, srv.registry().size(), srv.registry().live(),
        srv.ws_connections());
    std::printf(
        "resident memory (sampled every 100 ms): start %.1f MiB, with the sessions created "
        "%.1f MiB, peak %.1f MiB, end %.1f MiB; threads: start %d, peak %d, end %d (this "
        "program's clients: %d)\n",
        sampler.start_rss(), loaded_rss, sampler.peak_rss(), end_rss, sampler.start_threads(),
        sampler.peak_threads(), end_threads, o.sessions + o.clients);
    // whether it levels off: the peak of each quarter of the load
    std::printf("resident memory peak by quarter of the load:");
    for (int q = 0; q < 4; ++q) {
      std::printf(" %.1f", sampler.peak_rss(load_start + q * length / 4,
                                            q == 3 ? Clock::time_point::max()
                                                   : load_start + (q + 1) * length / 4));
    }
    std::printf(" MiB\n");
    if (errors + failures.load() > 0) status = 1;
    if (o.max_rss_mib > 0 && sampler.peak_rss() > o.max_rss_mib) {
      std::printf("FAIL: peak resident memory %.1f MiB is above the bound of %.1f MiB\n",
                  sampler.peak_rss(), o.max_rss_mib);
      status = 1;
    }
    srv.stop();
  } catch (const std::exception& e) {
    std::cerr << "mixed load: " << e.what() << "\n";
    status = 1;
  }
  std::error_code ignored;
  fs::remove_all(base, ignored);
  return status;
}

}  // namespace server_bench
