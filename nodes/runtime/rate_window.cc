/// @file rate_window.cc
/// @brief Rate statistics over a window of periods.
#include "nodes/runtime/rate_window.h"

#include <algorithm>
#include <cmath>

namespace p2i::runtime {

void RateWindow::Add(double t_s) {
  if (has_last_) {
    periods_.push_back(t_s - last_);
    if (window_ > 0 && periods_.size() > window_) periods_.pop_front();
  }
  last_ = t_s;
  has_last_ = true;
}

RateWindow::Summary RateWindow::Summarize() const {
  Summary s;
  if (periods_.empty()) return s;
  s.periods = periods_.size();
  double sum = 0;
  s.min_s = s.max_s = periods_.front();
  for (double p : periods_) {
    sum += p;
    s.min_s = std::min(s.min_s, p);
    s.max_s = std::max(s.max_s, p);
  }
  s.mean_s = sum / periods_.size();
  double var = 0;
  for (double p : periods_) var += (p - s.mean_s) * (p - s.mean_s);
  s.stddev_s = std::sqrt(var / periods_.size());
  s.rate_hz = s.mean_s > 0 ? 1.0 / s.mean_s : 0;
  return s;
}

}  // namespace p2i::runtime
