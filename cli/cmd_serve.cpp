// `pindrag serve`: the posing server (HTTP on --port, WebSocket on --ws-port) until SIGINT or
// SIGTERM, then a clean shutdown in which every session saves its last state.
#include <pthread.h>
#include <signal.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "cli/commands.hpp"
#include "server/security.hpp"
#include "server/server.hpp"

namespace cli {
namespace {

// $XDG_DATA_HOME/pindrag, else ~/.local/share/pindrag, else ./pindrag-data.
std::string default_data_dir() {
  if (const char* xdg = std::getenv("XDG_DATA_HOME"); xdg && *xdg)
    return std::string(xdg) + "/pindrag";
  if (const char* home = std::getenv("HOME"); home && *home)
    return std::string(home) + "/.local/share/pindrag";
  return "pindrag-data";
}

int serve(const server::ServerOptions& options) {
  // block the stop signals in every thread the server starts; this thread waits for them
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  // a write past a file size limit fails (EFBIG) and is reported on the edit, like a full disk,
  // instead of killing the server
  signal(SIGXFSZ, SIG_IGN);

  if (!server::is_loopback_host(options.host)) {
    std::cerr << "pindrag serve: WARNING: listening on " << options.host
              << ", not loopback only: other machines can reach this server. Every session "
                 "needs its token, and creating or listing sessions needs the server key in the "
                 "URL below.\n";
  }
  std::unique_ptr<server::Server> srv;
  try {
    srv = std::make_unique<server::Server>(options);
  } catch (const std::exception& e) {
    std::cerr << "pindrag serve: " << e.what() << "\n";
    return 1;
  }
  srv->start();
  std::cout << "pindrag serve: sessions in "
            << (options.data_dir.empty() ? "memory" : options.data_dir) << " ("
            << srv->restored_sessions() << " restored); WebSocket on port " << srv->ws_port()
            << "\n"
            << "Open " << srv->url() << std::endl;
  int signal_number = 0;
  sigwait(&stop_signals, &signal_number);
  std::cout << "pindrag serve: stopping (signal " << signal_number << ")" << std::endl;
  srv->stop();
  return 0;
}

// The budgets of docs/protocol.md, "Limits": every session's and every upload's.
void add_limit_options(CLI::App& cmd, server::ServerOptions& o) {
  animator::Limits& l = o.limits;
  cmd.add_option("--max-clip-seconds", l.max_clip_seconds, "longest clip or key time (seconds)")
      ->capture_default_str()
      ->check(CLI::Range(1e-3, 1e9))
      ->group("Limits");
  cmd.add_option("--max-clip-frames", l.max_clip_frames, "most frames of one clip")
      ->capture_default_str()
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{2'000'000'000}))
      ->group("Limits");
  cmd.add_option("--max-clip-values", l.max_clip_values,
                 "most numbers of one clip (frames x coordinates)")
      ->capture_default_str()
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 40))
      ->group("Limits");
  cmd.add_option("--max-keys", l.max_keys, "most keys of a session")
      ->capture_default_str()
      ->check(CLI::Range(1, 1'000'000'000))
      ->group("Limits");
  cmd.add_option("--max-layers", l.max_layers, "most edit layers of a session")
      ->capture_default_str()
      ->check(CLI::Range(1, 1'000'000'000))
      ->group("Limits");
  const auto bytes = [&cmd](const char* name, std::size_t& value, const char* what) {
    cmd.add_option(name, value, std::string(what) + " (bytes; 64MiB, 512KiB, ... also work)")
        ->capture_default_str()
        ->transform(CLI::AsSizeValue(false))
        ->group("Limits");
  };
  bytes("--max-undo-bytes", l.max_undo_bytes, "undo history memory of a session");
  bytes("--max-upload-urdf", o.uploads.urdf, "largest .urdf upload");
  bytes("--max-upload-json", o.uploads.json, "largest character .json upload");
  bytes("--max-upload-bvh", o.uploads.bvh, "largest .bvh upload");
  bytes("--max-upload-gltf", o.uploads.gltf, "largest .gltf or .glb upload");
  bytes("--max-upload-fbx", o.uploads.fbx, "largest .fbx upload");
  bytes("--max-upload-dae", o.uploads.dae, "largest .dae upload");
  bytes("--max-upload-c3d", o.uploads.c3d,
        "largest .c3d upload (a marker trial, fitted on upload)");
}

}  // namespace

void add_serve_command(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("serve", "serve the posing page and its WebSocket (open the printed URL)");
  auto options = std::make_shared<server::ServerOptions>();
  options->data_dir = default_data_dir();
  cmd->add_option("--host", options->host,
                  "address to listen on (loopback unless you need otherwise)")
      ->capture_default_str();
  cmd->add_option("--port", options->port, "HTTP port (0: any free port)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--ws-port", options->ws_port, "WebSocket port (default: --port + 1)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--character", options->character,
                  "bundled character name or character file offered to the page")
      ->capture_default_str();
  cmd->add_option("--data-dir", options->data_dir,
                  "folder where sessions are saved and restored from")
      ->capture_default_str();
  cmd->add_option("--web-root", options->web_root,
                  "folder of the page (default: the source tree's web/)");
  cmd->add_option("--max-live-sessions", options->max_live_sessions,
                  "sessions kept in memory at once; the least recently used idle one is saved "
                  "and unloaded to make room (stored sessions are not limited)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--expire-days", options->expire_days,
                  "delete saved sessions nobody opened or changed for this many days (0: never)")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000));
  cmd->add_option("--actor-threads", options->actor_threads,
                  "threads that run the sessions' edits and solver ticks, shared by all sessions "
                  "(0: one per core, at least 2)")
      ->capture_default_str()
      ->check(CLI::Range(0, 256));
  add_limit_options(*cmd, *options);
  cmd->callback([options] {
    const int code = serve(*options);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace cli
