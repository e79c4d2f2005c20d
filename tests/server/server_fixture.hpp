// The server fixture of the integration tests: a real server (server/server.hpp) on ephemeral
// loopback ports over a data folder and a web root of its own, with small clients for it.
// A test suite derives from ServerTest and may override configure() to change the options.
#pragma once

// Eigen (through the server's headers) before httplib.h: see server/http_routes.hpp
#include "server/protocol.hpp"
#include "server/server.hpp"
#include "tests/server/ws_test_client.hpp"

#include <gtest/gtest.h>
#include <httplib.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

namespace server_test {

using nlohmann::json;
namespace fs = std::filesystem;

// A web root of our own: the page, a script, three.js's layout, a secret beside it and a
// symlink pointing out of it.
inline fs::path make_web_root(const fs::path& base) {
  const fs::path root = base / "web";
  fs::create_directories(root / "js");
  fs::create_directories(root / "node_modules" / "three" / "build");
  std::ofstream(root / "index.html") << "<!doctype html><title>pindrag</title>";
  std::ofstream(root / "js" / "main.js") << "export const ok = 1;";
  std::ofstream(root / "node_modules" / "three" / "build" / "three.module.js")
      << "export const REVISION = '0';";
  std::ofstream(root / "node_modules" / "three" / "package.json") << "{\"secret\": true}";
  std::ofstream(base / "secret.txt") << "root:x:0:0:secret";
  fs::create_symlink(base / "secret.txt", root / "link_out.txt");
  return root;
}

class ServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::temp_directory_path() /
            ("pindrag-server-test-" + std::to_string(::getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(base_);
    fs::create_directories(base_);
    web_root_ = make_web_root(base_);
    start();
  }
  void TearDown() override {
    server_.reset();
    std::error_code ec;
    fs::remove_all(base_, ec);
  }

  /// Changes the options before each start (and restart).
  virtual void configure(server::ServerOptions&) {}
  void start() {
    server::ServerOptions options;
    options.port = 0;
    options.ws_port = 0;
    options.data_dir = (base_ / "data").string();
    options.web_root = web_root_.string();
    configure(options);
    server_ = std::make_unique<server::Server>(options);
    server_->start();
  }
  void restart() {
    server_.reset();
    start();
  }

  std::string origin() const { return "http://127.0.0.1:" + std::to_string(server_->http_port()); }
  httplib::Client http() const {
    httplib::Client c("127.0.0.1", server_->http_port());
    c.set_read_timeout(30, 0);
    return c;
  }

  struct Created {
    std::string id, token;
  };
  Created create_session(const std::string& character = "human48",
                         const httplib::Headers& extra = {}) {
    auto c = http();
    httplib::Headers headers{{"Origin", origin()}};
    headers.insert(extra.begin(), extra.end());
    const auto res =
        c.Post("/api/sessions", headers, json{{"character", character}}.dump(), "application/json");
    EXPECT_TRUE(res);
    if (!res) return {};
    EXPECT_EQ(res->status, 201) << res->body;
    const json j = json::parse(res->body);
    return {j.at("id"), j.at("token")};
  }
  json snapshot(const Created& s) {
    auto c = http();
    const auto res = c.Get("/api/sessions/" + s.id, {{"X-Session-Token", s.token}});
    EXPECT_TRUE(res);
    EXPECT_EQ(res->status, 200) << res->body;
    return json::parse(res->body);
  }
  std::unique_ptr<WsClient> connect(const Created& s) {
    auto ws = std::make_unique<WsClient>(server_->ws_port(),
                                         "/ws?session=" + s.id + "&token=" + s.token, origin());
    ws->send({{"type", "hello"}, {"protocol", 1}});
    return ws;
  }
  // Sends a message with an id and waits for its ack; fails on an error reply.
  void request(WsClient& ws, json message, int id) {
    message["id"] = id;
    ws.send(message);
    for (;;) {
      const server_test::WsMessage m = ws.read();
      if (!m.text) continue;
      const json j = m.json();
      if (j.value("type", "") == "error" && j.value("id", -1) == id) FAIL() << j.dump();
      if (j.value("type", "") == "ack" && j.value("id", -1) == id) {
        EXPECT_EQ(j.at("request"), message.at("type"));
        return;
      }
    }
  }
  std::shared_ptr<server::SessionActor> actor_of(const Created& s) {
    return server_->registry().find(s.id, s.token).actor;
  }

  fs::path base_, web_root_;
  std::unique_ptr<server::Server> server_;
};

}  // namespace server_test
