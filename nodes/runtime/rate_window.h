/// @file rate_window.h
/// @brief Message rate statistics over a window of arrival times (what `p2i topic hz` prints).
#pragma once

#include <cstddef>
#include <deque>

namespace p2i::runtime {

/// Keeps the last `window` periods between arrivals and summarises them like `ros2 topic hz`:
/// average rate = 1 / mean period, min / max / population std dev of the period.
/// Thread-compatible.
class RateWindow {
 public:
  struct Summary {
    size_t periods = 0;  ///< periods in the window (messages - 1)
    double rate_hz = 0;
    double min_s = 0, max_s = 0, stddev_s = 0, mean_s = 0;
  };

  explicit RateWindow(size_t window = 10000) : window_(window) {}
  /// Records an arrival at time `t_s` (seconds, monotonic).
  void Add(double t_s);
  /// Statistics of the current window (all zero if fewer than two arrivals).
  Summary Summarize() const;

 private:
  size_t window_;
  bool has_last_ = false;
  double last_ = 0;
  std::deque<double> periods_;
};

}  // namespace p2i::runtime
