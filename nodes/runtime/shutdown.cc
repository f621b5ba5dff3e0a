/// @file shutdown.cc
/// @brief Signal handling through a self-pipe so zmq_poll wakes immediately.
#include "nodes/runtime/shutdown.h"

#include <algorithm>
#include <cstdint>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <mutex>

namespace p2i::runtime {
namespace {

std::atomic<bool> g_requested{false};
int g_pipe[2] = {-1, -1};
std::once_flag g_pipe_once;

void MakePipe() {
  std::call_once(g_pipe_once, [] {
    if (pipe(g_pipe) == 0) {
      for (int fd : g_pipe) {
        fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
        fcntl(fd, F_SETFD, FD_CLOEXEC);
      }
    }
  });
}

extern "C" void OnSignal(int) { Shutdown::Request(); }

}  // namespace

void Shutdown::InstallSignalHandlers() {
  MakePipe();
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  // A node's stdout/stderr are often pipes to `p2i launch`; when the launcher dies, a write
  // must fail with EPIPE (ignored by the logger) instead of killing the node before its
  // OnShutdown() has flushed its files.
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGPIPE, &ignore, nullptr);
}

void Shutdown::Request() {
  // Async-signal-safe: lock-free atomic and write(). pipe created before handlers are set.
  g_requested.store(true);
  if (g_pipe[1] >= 0) {
    const char c = 1;
    const int saved = errno;
    (void)!write(g_pipe[1], &c, 1);
    errno = saved;
  }
}

bool Shutdown::Requested() { return g_requested.load(); }

int Shutdown::WakeFd() {
  MakePipe();
  return g_pipe[0];
}

bool Shutdown::WaitFor(std::chrono::nanoseconds d) {
  if (Requested()) return true;
  pollfd p{WakeFd(), POLLIN, 0};
  // A negative timeout would make poll() wait forever (a deadline already past when the
  // caller computed what is left of it): clamp to 0.
  const auto ms = std::max<int64_t>(0, std::chrono::duration_cast<std::chrono::milliseconds>(d).count());
  poll(&p, 1, static_cast<int>(std::min<int64_t>(ms, INT32_MAX)));
  return Requested();
}

void Shutdown::ResetForTesting() {
  MakePipe();
  char buf[64];
  while (read(g_pipe[0], buf, sizeof(buf)) > 0) {
  }
  g_requested.store(false);
}

}  // namespace p2i::runtime
