// `pindrag serve` run as a process under a small descriptor limit (RLIMIT_NOFILE): when the
// WebSocket port has more connections waiting than the server has descriptors left, its accept
// loop waits instead of spinning (the process's CPU time stays low), says so once, and accepts
// again once descriptors are free.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/sanitizers.hpp"
#include "tests/server/ws_test_client.hpp"

namespace {

namespace fs = std::filesystem;

// A child `pindrag serve` with a descriptor limit; stdout read until it prints its URL.
class ServeProcess {
 public:
  ServeProcess(const fs::path& base, rlim_t max_descriptors) {
    fs::create_directories(base / "web");
    std::ofstream(base / "web" / "index.html") << "<!doctype html><title>pindrag</title>";
    stderr_path_ = base / "stderr.txt";
    const std::vector<std::string> args{PINDRAG_EXE,  "serve",
                                        "--port",     "0",
                                        "--ws-port",  "0",
                                        "--data-dir", (base / "data").string(),
                                        "--web-root", (base / "web").string()};
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    int out[2];
    if (::pipe(out) != 0) return;
    const int err = ::open(stderr_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    pid_ = ::fork();
    if (pid_ == 0) {
      // the child: only async-signal-safe calls until exec
      const rlimit limit{max_descriptors, max_descriptors};
      ::setrlimit(RLIMIT_NOFILE, &limit);
      ::dup2(out[1], 1);
      ::dup2(err, 2);
      ::close(out[0]);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    ::close(out[1]);
    ::close(err);
    // "... WebSocket on port N" then "Open http://127.0.0.1:P/"
    std::string text;
    char chunk[512];
    const std::regex ws(R"(WebSocket on port (\d+))");
    const std::regex open(R"(Open http://[^:]+:(\d+)/)");
    std::smatch m;
    while (!std::regex_search(text, m, open)) {
      const ssize_t n = ::read(out[0], chunk, sizeof chunk);
      if (n <= 0) break;
      text.append(chunk, static_cast<size_t>(n));
    }
    out_ = out[0];
    if (std::regex_search(text, m, open)) http_port = std::stoi(m[1]);
    if (std::regex_search(text, m, ws)) ws_port = std::stoi(m[1]);
  }
  ~ServeProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (out_ >= 0) ::close(out_);
  }
  // CPU time (user + system) of the child so far, in seconds
  double cpu_seconds() const {
    std::ifstream stat("/proc/" + std::to_string(pid_) + "/stat");
    std::string line;
    std::getline(stat, line);
    std::istringstream fields(line.substr(line.rfind(')') + 2));
    std::string field;
    long utime = 0, stime = 0;
    for (int i = 3; i <= 15 && fields >> field; ++i) {
      if (i == 14) utime = std::stol(field);
      if (i == 15) stime = std::stol(field);
    }
    return static_cast<double>(utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK));
  }
  // SIGTERM, then the exit code (-1 when it did not exit by itself)
  int stop() {
    ::kill(pid_, SIGTERM);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  std::string stderr_text() const {
    std::ifstream in(stderr_path_);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

  int http_port = 0;
  int ws_port = 0;

 private:
  pid_t pid_ = -1;
  int out_ = -1;
  fs::path stderr_path_;
};

int connect_to(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(ServeProcess, AcceptAtTheDescriptorLimitWaitsInsteadOfSpinning) {
#ifdef PINDRAG_ASAN
  // UBSan's vptr check opens a pipe to probe memory; with no descriptor left it reports every
  // dynamic type it checks as invalid, so the sanitized server cannot run at its limit
  GTEST_SKIP() << "needs descriptors the sanitizer runtime takes; runs in the optimized build";
#endif
  const fs::path base =
      fs::temp_directory_path() / ("pindrag-serve-process-" + std::to_string(::getpid()));
  fs::remove_all(base);
  ServeProcess serve(base, 64);
  ASSERT_GT(serve.ws_port, 0) << serve.stderr_text();

  // more connections than the server has descriptors: they wait in the listen backlog
  std::vector<int> clients;
  for (int i = 0; i < 120; ++i) {
    const int fd = connect_to(serve.ws_port);
    ASSERT_GE(fd, 0);
    clients.push_back(fd);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const double cpu0 = serve.cpu_seconds();
  std::this_thread::sleep_for(std::chrono::seconds(2));
  const double cpu = serve.cpu_seconds() - cpu0;
  std::cout << "at the descriptor limit: " << cpu << " s of CPU in 2 s\n";
  EXPECT_LT(cpu, 0.3) << "the accept loop spins at the descriptor limit";

  // descriptors come back: it accepts again (a plain GET on the WebSocket port gets its 400)
  for (const int fd : clients) ::close(fd);
  const auto reply = server_test::raw_http(
      serve.ws_port, "GET /ws HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(serve.ws_port) +
                         "\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(reply.status, 400) << reply.body;
  EXPECT_EQ(serve.stop(), 0);
  const std::string log = serve.stderr_text();
  // said once per episode, not once per retry (eight retries fit in the two seconds)
  EXPECT_GE(count(log, "WebSocket accept failed"), 1u) << log;
  EXPECT_LE(count(log, "WebSocket accept failed"), 3u) << log;
  EXPECT_GE(count(log, "WebSocket accepting again"), 1u) << log;
  fs::remove_all(base);
}

}  // namespace
