// Runs untrusted work (a third-party importer fed a user's file) in a forked child process with
// resource limits, and brings back only the bytes the child writes to a pipe. Whatever the
// child does — crash, exhaust its memory or CPU, hang, write garbage or too much — the parent
// gets a status and a message, never a crash, and never leaves a zombie behind.
//
// The child: closes every inherited descriptor but its end of the pipe, dies with the parent
// (PR_SET_PDEATHSIG), gets no core file and may not write files (RLIMIT_CORE = RLIMIT_FSIZE = 0),
// may grow its address space by `memory_bytes` beyond what it inherited (RLIMIT_AS), may use
// `cpu_seconds` of CPU (RLIMIT_CPU soft limit: SIGXCPU; hard limit one second later: SIGKILL),
// runs the work and leaves with _exit (no atexit handlers, no stdio flush of the parent's buffers,
// no leak check). std::bad_alloc from the work becomes exit status kSandboxOutOfMemory.
//
// The parent: reads the pipe with a wall-clock deadline and a size cap, kills the child
// (SIGKILL) when either is exceeded, and always reaps it with wait4.
//
// Caveat: fork() copies only the calling thread. In a multithreaded parent the work must not
// need a lock another thread held at the fork; glibc resets malloc's locks, and a child that
// deadlocks anyway is killed at the deadline.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include "io/core_names.hpp"

namespace io {

struct SandboxLimits {
  std::size_t memory_bytes = std::size_t{512} << 20;  // address space beyond the inherited one
  int cpu_seconds = 20;                               // CPU time (soft limit; hard = soft + 1)
  double timeout_seconds = 60;                        // wall clock, from fork to exit
  std::size_t max_reply_bytes = std::size_t{256} << 20;
};

enum class SandboxStatus {
  kOk,             // the work returned and the child exited with status 0
  kStartFailed,    // pipe() or fork() failed in the parent
  kMemoryLimit,    // the work ran out of memory under its limit
  kCpuLimit,       // killed by SIGXCPU or by the hard CPU limit
  kTimeout,        // still running at the deadline; killed
  kReplyTooLarge,  // wrote more than max_reply_bytes; killed
  kCrashed,        // killed by another signal, or exited with another status
};

struct SandboxResult {
  SandboxStatus status = SandboxStatus::kStartFailed;
  std::string reply;  // everything the child wrote (complete only for kOk)
  std::string
      message;  // what happened, for kOk empty: e.g. "crashed (signal 11, Segmentation fault)"
  int exit_status = -1;  // exit status, or -1 when killed by a signal
  int signal = 0;        // terminating signal, or 0
};

/// Exit status of a child whose work threw std::bad_alloc (or, under AddressSanitizer, whose
/// allocator reported running out of memory).
constexpr int kSandboxOutOfMemory = 86;
/// Exit status of a child whose work threw anything else.
constexpr int kSandboxUncaughtException = 87;

/// Runs work(fd) in a child process under `limits`. The work writes its reply to fd (a pipe;
/// write_all() below handles partial writes) and returns its exit status (0 for success).
SandboxResult run_sandboxed(const std::function<int(int fd)>& work, const SandboxLimits& limits);

/// Writes all of `bytes` to fd, retrying partial writes and EINTR; false on error.
bool write_all(int fd, const void* bytes, std::size_t size);

}  // namespace io
