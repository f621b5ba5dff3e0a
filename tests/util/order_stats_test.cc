/// @file order_stats_test.cc
/// @brief Median and percentiles: exact values, NaN and inf dropped, empty input, bad p.
#include "util/order_stats.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <catch2/catch.hpp>

#include "util/json_number.h"

namespace p2i::util {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST_CASE("Median and percentiles of finite values, NaN and inf are dropped", "[unit]") {
  const std::vector<double> v = {5, 1, kNaN, 4, 2, kInf, 3};  // finite: 1 2 3 4 5
  CHECK(FiniteValues(v) == std::vector<double>{5, 1, 4, 2, 3});
  CHECK(Median(v) == 3.0);
  CHECK(Median({4, 1, 3, 2}) == 2.5);          // even count: mean of the middle two
  CHECK(Median({1, 2, kNaN, kNaN, kNaN}) == 1.5);  // v[n/2] of the raw list would be NaN
  CHECK(PercentileNearestRank(v, 50) == 3.0);
  CHECK(PercentileNearestRank(v, 99) == 5.0);
  CHECK(PercentileNearestRank(v, 0) == 1.0);
  CHECK(PercentileNearestRank(v, 20) == 1.0);  // ceil(0.2 * 5) = 1st
  CHECK(PercentileNearestRank(v, 21) == 2.0);
  CHECK(PercentileLinear(v, 90) == Approx(4.6));  // numpy.percentile([1..5], 90)
  CHECK(PercentileLinear(v, 100) == 5.0);
  CHECK(std::isnan(Median({})));
  CHECK(std::isnan(Median({kNaN, kInf})));
  CHECK(std::isnan(PercentileNearestRank({}, 50)));
  CHECK_THROWS_AS(PercentileLinear(v, 101), std::invalid_argument);
  CHECK_THROWS_AS(PercentileNearestRank(v, -1), std::invalid_argument);
}

TEST_CASE("NumberOrNull writes missing measurements as null", "[unit]") {
  CHECK(NumberOrNull(1.5).dump() == "1.5");
  CHECK(NumberOrNull(kNaN).is_null());
  CHECK(NumberOrNull(-kInf).is_null());
}

}  // namespace
}  // namespace p2i::util
