/// @file error_stats.cc
/// @brief ErrorSummary.
#include "nodes/slam_sink/error_stats.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace p2i::slam_sink {

double ErrorSummary::Quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(sorted.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  const double frac = pos - static_cast<double>(lo);
  return sorted[lo] + frac * (sorted[hi] - sorted[lo]);
}

ErrorSummary ErrorSummary::Of(std::vector<double> values) {
  ErrorSummary s;
  values.erase(std::remove_if(values.begin(), values.end(),
                              [](double v) { return !std::isfinite(v); }),
               values.end());
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  s.count = values.size();
  s.mean = std::accumulate(values.begin(), values.end(), 0.0) / values.size();
  s.median = Quantile(values, 0.5);
  s.p90 = Quantile(values, 0.9);
  s.max = values.back();
  return s;
}

}  // namespace p2i::slam_sink
