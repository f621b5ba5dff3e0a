/// @file executor.cc
/// @brief Single-threaded event loop over zmq_poll.
#include "nodes/runtime/executor.h"

#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>

#include "nodes/runtime/shutdown.h"
#include "nodes/runtime/wire_io.h"

namespace p2i::runtime {

Executor::Executor() { wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC); }

Executor::~Executor() {
  if (wake_fd_ >= 0) close(wake_fd_);
}

void Executor::AddSocket(zmq::socket_t* socket, Callback on_readable) {
  sockets_.push_back({socket, std::move(on_readable)});
}

void Executor::RemoveSocket(zmq::socket_t* socket) {
  sockets_.erase(std::remove_if(sockets_.begin(), sockets_.end(),
                                [&](const SocketEntry& e) { return e.socket == socket; }),
                 sockets_.end());
}

int Executor::AddTimer(std::chrono::nanoseconds period, Callback cb) {
  const int id = next_timer_id_++;
  timers_.push_back({id, period, Clock::now() + period, std::move(cb)});
  return id;
}

void Executor::CancelTimer(int id) {
  timers_.erase(std::remove_if(timers_.begin(), timers_.end(),
                               [&](const Timer& t) { return t.id == id; }),
                timers_.end());
}

void Executor::Post(Callback task) {
  {
    std::lock_guard<std::mutex> lock(post_mutex_);
    posted_.push_back(std::move(task));
  }
  Wake();
}

void Executor::Wake() {
  const uint64_t one = 1;
  (void)!write(wake_fd_, &one, sizeof(one));
}

void Executor::DrainWakeFd() {
  uint64_t v;
  (void)!read(wake_fd_, &v, sizeof(v));
}

void Executor::Stop() {
  stopped_.store(true);
  Wake();
}

bool Executor::Stopped() const { return stopped_.load() || Shutdown::Requested(); }

bool Executor::SpinOnce(std::chrono::nanoseconds max_wait) {
  if (Stopped()) return false;
  auto now = Clock::now();
  auto deadline = now + max_wait;
  for (const auto& t : timers_) deadline = std::min(deadline, t.next);

  std::vector<zmq::pollitem_t> items;
  items.reserve(sockets_.size() + 2);
  items.push_back({nullptr, Shutdown::WakeFd(), ZMQ_POLLIN, 0});
  items.push_back({nullptr, wake_fd_, ZMQ_POLLIN, 0});
  for (auto& s : sockets_) items.push_back({s.socket->handle(), 0, ZMQ_POLLIN, 0});
  // Round up: waking a fraction of a millisecond early would spin until the timer is due.
  const auto wait = std::max<int64_t>(
      0, std::chrono::ceil<std::chrono::milliseconds>(deadline - now).count());
  Poll(items.data(), items.size(), std::chrono::milliseconds(wait));
  if (Stopped()) return false;

  if (items[1].revents & ZMQ_POLLIN) DrainWakeFd();
  std::vector<Callback> tasks;
  {
    std::lock_guard<std::mutex> lock(post_mutex_);
    tasks.swap(posted_);
  }
  for (auto& t : tasks) t();

  // Copy the socket list: a callback may add or remove sockets.
  std::vector<std::pair<zmq::socket_t*, Callback>> ready;
  for (size_t i = 2; i < items.size(); ++i) {
    if (items[i].revents & ZMQ_POLLIN) ready.emplace_back(sockets_[i - 2].socket, sockets_[i - 2].cb);
  }
  for (auto& [sock, cb] : ready) {
    if (Stopped()) return false;
    cb();
  }

  now = Clock::now();
  std::vector<int> due;
  for (auto& t : timers_) {
    if (t.next <= now) due.push_back(t.id);
  }
  for (int id : due) {
    auto it = std::find_if(timers_.begin(), timers_.end(), [&](const Timer& t) { return t.id == id; });
    if (it == timers_.end()) continue;  // cancelled by an earlier callback
    it->next += it->period;
    if (it->next <= now) it->next = now + it->period;
    Callback cb = it->cb;  // copy: the callback may cancel its own timer
    cb();
    if (Stopped()) return false;
  }
  return !Stopped();
}

void Executor::Spin() {
  while (SpinOnce()) {
  }
}

}  // namespace p2i::runtime
