/// @file shutdown.h
/// @brief Process-wide stop request: SIGINT/SIGTERM (or a call) set a flag and wake pollers.
#pragma once

#include <chrono>

namespace p2i::runtime {

/// The process-wide stop flag.
///
/// InstallSignalHandlers() makes SIGINT and SIGTERM call Request() (async-signal-safe: an atomic
/// store and a write() to a self-pipe) and ignores SIGPIPE (a write to a dead launcher's pipe fails
/// with EPIPE instead of killing the node). Loops either poll Requested(), include WakeFd() in their
/// zmq_poll set (it becomes readable on a request), or block in WaitFor(). Thread-safe.
class Shutdown {
 public:
  static void InstallSignalHandlers();
  static void Request();
  static bool Requested();
  /// Read end of the self-pipe; readable once a stop was requested (never drained).
  static int WakeFd();
  /// Sleeps up to `d`; returns true (early) if a stop is requested.
  static bool WaitFor(std::chrono::nanoseconds d);
  /// Clears the flag (tests that run several nodes in one process).
  static void ResetForTesting();
};

}  // namespace p2i::runtime
