/// @file latest_slot.h
/// @brief A one-element mailbox that keeps only the newest item (latest-only request handling).
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <utility>

namespace p2i::nodes {

/// Holds at most one pending item. Put() replaces an item not yet taken (the caller counts that
/// as skipped: under overload the newest request wins, older ones are dropped, not queued).
/// Take() waits for an item or Close().
///
/// Thread-safety: thread-safe; any number of producers and consumers.
template <class T>
class LatestSlot {
 public:
  /// Stores `item`; returns true when it replaced an item that was never taken.
  bool Put(T item) {
    bool replaced = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      replaced = item_.has_value();
      item_ = std::move(item);
    }
    cv_.notify_one();
    return replaced;
  }

  /// The pending item, waiting up to `timeout`; nullopt on timeout or after Close().
  std::optional<T> Take(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_for(lock, timeout, [this] { return closed_ || item_.has_value(); });
    if (closed_ || !item_) return std::nullopt;
    std::optional<T> out = std::move(item_);
    item_.reset();
    return out;
  }

  /// Wakes every waiter; later Take() calls return nullopt at once.
  void Close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    cv_.notify_all();
  }

  bool Empty() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return !item_.has_value();
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::optional<T> item_;
  bool closed_ = false;
};

}  // namespace p2i::nodes
