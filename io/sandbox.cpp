#include "io/sandbox.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <new>

#include "core/sanitizers.hpp"
#ifdef PINDRAG_ASAN
#include <sanitizer/asan_interface.h>
#include <sanitizer/common_interface_defs.h>
#endif

namespace io {

using namespace core;  // io reads and writes core's types

namespace {

using Clock = std::chrono::steady_clock;

// the address space of this process (bytes), from /proc/self/statm; 0 when unknown.
// Read with open/read only: it runs in the child right after fork.
std::size_t address_space_size() {
  const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  char buf[128];
  const ssize_t n = ::read(fd, buf, sizeof buf - 1);
  ::close(fd);
  if (n <= 0) return 0;
  std::size_t pages = 0;
  for (ssize_t i = 0; i < n && buf[i] >= '0' && buf[i] <= '9'; ++i) {
    pages = pages * 10 + static_cast<std::size_t>(buf[i] - '0');
  }
  return pages * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
}

void set_limit(int resource, rlim_t soft, rlim_t hard) {
  rlimit r{};
  ::getrlimit(resource, &r);
  // never raise a limit the parent already lowered
  if (r.rlim_max != RLIM_INFINITY) {
    hard = std::min(hard, r.rlim_max);
    soft = std::min(soft, hard);
  }
  r.rlim_cur = soft;
  r.rlim_max = hard;
  ::setrlimit(resource, &r);
}

// every descriptor but 0, 1, 2 and `keep`: the child sees none of the parent's files or sockets
void close_inherited(int keep) {
  const unsigned int k = static_cast<unsigned int>(keep);
  if (k > 3) ::syscall(SYS_close_range, 3u, k - 1, 0u);
  ::syscall(SYS_close_range, k + 1, ~0u, 0u);
}

#ifdef PINDRAG_ASAN
// AddressSanitizer's allocator cannot return null to operator new: when the address-space limit
// stops it, it reports "out-of-memory" and dies. Report that as the out-of-memory status.
void on_sanitizer_death() {
  if (__asan_report_present() &&
      std::strcmp(__asan_get_report_description(), "out-of-memory") == 0) {
    ::_exit(kSandboxOutOfMemory);
  }
}
#endif

[[noreturn]] void child_main(const std::function<int(int)>& work,
                             const SandboxLimits& limits,
                             int fd,
                             pid_t parent) {
  // die with the parent; if it is already gone, do not start
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) ::_exit(kSandboxUncaughtException);
  close_inherited(fd);
  ::signal(SIGPIPE, SIG_DFL);
  set_limit(RLIMIT_CORE, 0, 0);
  set_limit(RLIMIT_FSIZE, 0, 0);
  const rlim_t cpu = static_cast<rlim_t>(std::max(1, limits.cpu_seconds));
  set_limit(RLIMIT_CPU, cpu, cpu + 1);
  const std::size_t base = address_space_size();
  set_limit(RLIMIT_AS, base + limits.memory_bytes, base + limits.memory_bytes);
#ifdef PINDRAG_ASAN
  __sanitizer_set_death_callback(&on_sanitizer_death);
#endif
  int status = 0;
  try {
    status = work(fd);
  } catch (const std::bad_alloc&) {
    ::_exit(kSandboxOutOfMemory);
  } catch (...) {
    ::_exit(kSandboxUncaughtException);
  }
  ::_exit(status);
}

// kills (when asked) and reaps the child; fills status, signal and CPU time
void reap(pid_t pid, bool kill_first, int& wstatus, double& cpu_seconds) {
  if (kill_first) ::kill(pid, SIGKILL);
  rusage ru{};
  while (::wait4(pid, &wstatus, 0, &ru) < 0 && errno == EINTR) {
  }
  cpu_seconds = static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

std::string describe_signal(int sig) {
  const char* name = ::strsignal(sig);
  return "signal " + std::to_string(sig) + (name != nullptr ? std::string(", ") + name : "");
}

std::string mib(std::size_t bytes) { return std::to_string(bytes >> 20) + " MiB"; }
std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", s);
  return buf;
}

}  // namespace

bool write_all(int fd, const void* bytes, std::size_t size) {
  const auto* p = static_cast<const char*>(bytes);
  while (size > 0) {
    const ssize_t w = ::write(fd, p, size);
    if (w < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    p += w;
    size -= static_cast<std::size_t>(w);
  }
  return true;
}

namespace {

enum class ReadEnd { kEndOfFile, kTimedOut, kTooLarge };

// reads the child's reply until end of file, the deadline or the size cap
ReadEnd read_reply(int fd, Clock::time_point deadline, std::size_t max_bytes, std::string& reply) {
  char buf[1 << 16];
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return ReadEnd::kTimedOut;
    pollfd p{fd, POLLIN, 0};
    const int r = ::poll(&p, 1, static_cast<int>(std::min<long long>(left.count(), 1000)));
    if (r < 0 && errno != EINTR) return ReadEnd::kEndOfFile;
    if (r <= 0) continue;
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      return ReadEnd::kEndOfFile;
    }
    if (n == 0) return ReadEnd::kEndOfFile;
    if (reply.size() + static_cast<std::size_t>(n) > max_bytes) return ReadEnd::kTooLarge;
    reply.append(buf, static_cast<std::size_t>(n));
  }
}

// the pipe is closed: waits for the child's exit until the deadline, then kills it; false when
// the deadline passed
bool wait_for_exit(pid_t pid, Clock::time_point deadline, int& wstatus, double& cpu) {
  for (;;) {
    rusage ru{};
    const pid_t w = ::wait4(pid, &wstatus, WNOHANG, &ru);
    if (w == pid) {
      cpu = static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
            1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
      return true;
    }
    if (w < 0 && errno != EINTR) return true;
    if (Clock::now() >= deadline) {
      reap(pid, true, wstatus, cpu);
      return false;
    }
    const timespec ts{0, 1000000};  // 1 ms
    ::nanosleep(&ts, nullptr);
  }
}

// what the child's end means for the caller
void classify(SandboxResult& result,
              const SandboxLimits& limits,
              bool timed_out,
              bool too_large,
              int wstatus,
              double cpu) {
  result.exit_status = WIFEXITED(wstatus) ? WEXITSTATUS(wstatus) : -1;
  result.signal = WIFSIGNALED(wstatus) ? WTERMSIG(wstatus) : 0;
  if (too_large) {
    result.status = SandboxStatus::kReplyTooLarge;
    result.message = "wrote more than " + mib(limits.max_reply_bytes) + " of results; stopped";
  } else if (timed_out) {
    result.status = SandboxStatus::kTimeout;
    result.message =
        "did not finish within " + seconds(limits.timeout_seconds) + " of wall-clock time; stopped";
  } else if (result.signal == SIGXCPU ||
             (result.signal == SIGKILL && cpu >= std::max(1, limits.cpu_seconds))) {
    result.status = SandboxStatus::kCpuLimit;
    result.message =
        "exceeded its CPU time limit of " + seconds(std::max(1, limits.cpu_seconds)) + "; stopped";
  } else if (result.exit_status == kSandboxOutOfMemory) {
    result.status = SandboxStatus::kMemoryLimit;
    result.message = "ran out of memory under its limit of " + mib(limits.memory_bytes);
  } else if (result.signal != 0) {
    result.status = SandboxStatus::kCrashed;
    result.message = "crashed (" + describe_signal(result.signal) + ")";
  } else if (result.exit_status == kSandboxUncaughtException) {
    result.status = SandboxStatus::kCrashed;
    result.message = "failed with an unexpected exception";
  } else if (result.exit_status != 0) {
    result.status = SandboxStatus::kCrashed;
    result.message = "exited with status " + std::to_string(result.exit_status);
  } else {
    result.status = SandboxStatus::kOk;
  }
}

}  // namespace

SandboxResult run_sandboxed(const std::function<int(int fd)>& work, const SandboxLimits& limits) {
  SandboxResult result;
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    result.message = std::string("cannot create a pipe: ") + std::strerror(errno);
    return result;
  }
  const pid_t parent = ::getpid();
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(std::max(0.0, limits.timeout_seconds)));
  const pid_t pid = ::fork();
  if (pid < 0) {
    result.message = std::string("cannot start a child process: ") + std::strerror(errno);
    ::close(fds[0]);
    ::close(fds[1]);
    return result;
  }
  if (pid == 0) child_main(work, limits, fds[1], parent);
  ::close(fds[1]);

  const ReadEnd end = read_reply(fds[0], deadline, limits.max_reply_bytes, result.reply);
  ::close(fds[0]);
  bool timed_out = end == ReadEnd::kTimedOut;
  const bool too_large = end == ReadEnd::kTooLarge;
  int wstatus = 0;
  double cpu = 0;
  if (!timed_out && !too_large) {
    timed_out = !wait_for_exit(pid, deadline, wstatus, cpu);
  } else {
    reap(pid, true, wstatus, cpu);
  }
  classify(result, limits, timed_out, too_large, wstatus, cpu);
  return result;
}

}  // namespace io

#undef PINDRAG_ASAN  // a batch build compiles the next file in this unit
