/// @file error_stats.cc
/// @brief ErrorSummary.
#include "nodes/slam_sink/error_stats.h"

#include <algorithm>
#include <numeric>

#include "util/order_stats.h"

namespace p2i::slam_sink {

ErrorSummary ErrorSummary::Of(std::vector<double> values) {
  ErrorSummary s;
  values = util::FiniteValues(values);
  if (values.empty()) return s;
  s.count = values.size();
  s.mean = std::accumulate(values.begin(), values.end(), 0.0) / values.size();
  s.median = util::Median(values);
  s.p90 = util::PercentileLinear(values, 90.0);
  s.max = *std::max_element(values.begin(), values.end());
  return s;
}

}  // namespace p2i::slam_sink
