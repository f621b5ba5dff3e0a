/// @file order_stats.h
/// @brief Median and percentiles of samples, the one implementation: non-finite values (NaN,
/// inf: a failed measurement) are dropped first, and no samples give NaN.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace p2i::util {

/// The finite values of `values`, in their order.
std::vector<double> FiniteValues(const std::vector<double>& values);

/// Nearest-rank percentile (the smallest value with at least p % of the samples at or below
/// it), p in [0, 100]: p50 / p99 of latencies. NaN when no value is finite. Throws
/// std::invalid_argument for p outside [0, 100].
double PercentileNearestRank(const std::vector<double>& values, double p);

/// Percentile by linear interpolation between order statistics (numpy's default), p in
/// [0, 100]. NaN when no value is finite. Throws std::invalid_argument for p outside [0, 100].
double PercentileLinear(const std::vector<double>& values, double p);

/// The median of the finite values (the mean of the middle two for an even count); NaN when
/// there are none.
double Median(const std::vector<double>& values);

}  // namespace p2i::util

// Implementation (header-only: p2i_util is an INTERFACE library, so the shared p2i_model and
// the executables that link it never hold two copies).
namespace p2i::util {
namespace detail {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

inline std::vector<double> SortedFinite(const std::vector<double>& values, double p,
                                        const char* what) {
  if (!(p >= 0.0 && p <= 100.0)) {
    throw std::invalid_argument(std::string(what) + ": p must be in [0, 100], got " +
                                std::to_string(p));
  }
  std::vector<double> v = FiniteValues(values);
  std::sort(v.begin(), v.end());
  return v;
}

}  // namespace detail

inline std::vector<double> FiniteValues(const std::vector<double>& values) {
  std::vector<double> out;
  out.reserve(values.size());
  for (double x : values)
    if (std::isfinite(x)) out.push_back(x);
  return out;
}

inline double PercentileNearestRank(const std::vector<double>& values, double p) {
  const std::vector<double> v = detail::SortedFinite(values, p, "PercentileNearestRank");
  if (v.empty()) return detail::kNaN;
  const auto rank = static_cast<size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())));
  return v[std::clamp<size_t>(rank, 1, v.size()) - 1];
}

inline double PercentileLinear(const std::vector<double>& values, double p) {
  const std::vector<double> v = detail::SortedFinite(values, p, "PercentileLinear");
  if (v.empty()) return detail::kNaN;
  const double pos = p / 100.0 * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

inline double Median(const std::vector<double>& values) { return PercentileLinear(values, 50.0); }

}  // namespace p2i::util
