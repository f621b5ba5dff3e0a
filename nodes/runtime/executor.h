/// @file executor.h
/// @brief One thread that waits on sockets and timers and runs their callbacks.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <vector>

#include <zmq.hpp>

namespace p2i::runtime {

/// A single-threaded event loop: socket-readable callbacks, periodic timers and posted tasks all
/// run on the thread that calls Spin()/SpinOnce(), one at a time, so node code needs no locks.
///
/// Thread-safety: AddSocket/AddTimer/RemoveSocket/CancelTimer/SpinOnce/Spin must be called from
/// the spinning thread (or before Spin starts). Post() and Stop() are thread-safe. The executor
/// also stops when Shutdown::Requested() (SIGINT/SIGTERM), waking at once through the signal
/// self-pipe. Sockets given to AddSocket are owned by the caller but used only on this thread.
class Executor {
 public:
  using Clock = std::chrono::steady_clock;
  using Callback = std::function<void()>;

  Executor();
  ~Executor();
  Executor(const Executor&) = delete;
  Executor& operator=(const Executor&) = delete;

  /// `on_readable` runs when `socket` has a message; it should drain what it wants.
  void AddSocket(zmq::socket_t* socket, Callback on_readable);
  void RemoveSocket(zmq::socket_t* socket);
  /// Runs `cb` every `period` (first run one period from now); returns an id for CancelTimer.
  /// A late timer runs once and is rescheduled from now (no catch-up bursts).
  int AddTimer(std::chrono::nanoseconds period, Callback cb);
  void CancelTimer(int id);
  /// Runs `task` on the executor thread soon. Thread-safe.
  void Post(Callback task);

  /// Waits up to `max_wait` for one round of events and runs what is due. Returns false once
  /// stopped (Stop() or a shutdown signal).
  bool SpinOnce(std::chrono::nanoseconds max_wait = std::chrono::milliseconds(100));
  /// Runs until Stop() or a shutdown signal.
  void Spin();
  /// Makes Spin() return soon. Thread-safe.
  void Stop();
  bool Stopped() const;

 private:
  struct SocketEntry {
    zmq::socket_t* socket;
    Callback cb;
  };
  struct Timer {
    int id;
    std::chrono::nanoseconds period;
    Clock::time_point next;
    Callback cb;
  };
  void Wake();
  void DrainWakeFd();

  std::vector<SocketEntry> sockets_;
  std::vector<Timer> timers_;
  int next_timer_id_ = 1;
  std::mutex post_mutex_;
  std::vector<Callback> posted_;
  std::atomic<bool> stopped_{false};
  int wake_fd_ = -1;  // eventfd for Post()/Stop()
};

}  // namespace p2i::runtime
