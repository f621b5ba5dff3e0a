/// @file error_stats.h
/// @brief Summary statistics (count, mean, median, p90, max) of a list of error values.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

namespace p2i::slam_sink {

/// A value type: thread-compatible. NaN fields when count == 0.
struct ErrorSummary {
  size_t count = 0;
  double mean = std::numeric_limits<double>::quiet_NaN();
  double median = std::numeric_limits<double>::quiet_NaN();
  double p90 = std::numeric_limits<double>::quiet_NaN();
  double max = std::numeric_limits<double>::quiet_NaN();

  /// Of the finite values; median and p90 by linear interpolation between order statistics
  /// (numpy's default, util::PercentileLinear).
  static ErrorSummary Of(std::vector<double> values);
};

}  // namespace p2i::slam_sink
