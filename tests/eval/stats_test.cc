/// @file stats_test.cc
/// @brief Pareto front, Spearman, spread, first-distance-below and the --auto-size choice.
#include <cmath>

#include <catch2/catch.hpp>

#include "eval/stats.h"

using namespace p2i::eval;

TEST_CASE("ParetoFront keeps exactly the non-dominated points", "[unit]") {
  // (speed, PSNR): a fast-bad, b slow-good, c dominated by b, d on the front between them.
  const std::vector<ParetoPoint> pts = {{1000, 15}, {10, 25}, {5, 20}, {100, 22}, {NAN, 30}};
  CHECK(ParetoFront(pts, true, true) == std::vector<size_t>{0, 1, 3});
  // Lower is better for y (LPIPS): now the lowest y wins at each speed.
  const std::vector<ParetoPoint> lp = {{1000, 0.5}, {10, 0.1}, {5, 0.05}, {100, 0.6}};
  CHECK(ParetoFront(lp, true, false) == std::vector<size_t>{0, 1, 2});
  // Duplicates are both kept; a point equal on one axis and worse on the other is dominated.
  const std::vector<ParetoPoint> dup = {{1, 1}, {1, 1}, {1, 0.5}};
  CHECK(ParetoFront(dup, true, true) == std::vector<size_t>{0, 1});
  CHECK(ParetoFront({}, true, true).empty());
}

TEST_CASE("SpearmanRho matches hand-computed values, with ties and missing data", "[unit]") {
  CHECK(SpearmanRho({1, 2, 3, 4, 5}, {10, 20, 30, 40, 50}) == Approx(1.0));
  CHECK(SpearmanRho({1, 2, 3, 4, 5}, {5, 4, 3, 2, 1}) == Approx(-1.0));
  // Monotone but non-linear: still 1.
  CHECK(SpearmanRho({1, 2, 3, 4}, {1, 8, 27, 1000}) == Approx(1.0));
  // Classic example: d = (0, 1, -1, 0, 0)... rho = 1 - 6 * sum d^2 / (n (n^2 - 1)) = 0.9.
  CHECK(SpearmanRho({1, 2, 3, 4, 5}, {1, 3, 2, 4, 5}) == Approx(0.9));
  // Ties get average ranks: x ranks (1.5, 1.5, 3, 4), y ranks (1, 2, 3, 4): Pearson of ranks.
  const double rho = SpearmanRho({7, 7, 8, 9}, {1, 2, 3, 4});
  CHECK(rho == Approx(0.9486833).epsilon(1e-6));
  CHECK(FractionalRanks({3, 1, 3, 2}) == std::vector<double>{3.5, 1, 3.5, 2});
  // NaN pairs are dropped; fewer than 3 pairs or a constant side give NaN.
  CHECK(SpearmanRho({1, NAN, 2, 3}, {1, 5, 2, 3}) == Approx(1.0));
  CHECK(std::isnan(SpearmanRho({1, 2}, {1, 2})));
  CHECK(std::isnan(SpearmanRho({1, 1, 1}, {1, 2, 3})));
  CHECK_THROWS_AS(SpearmanRho({1, 2, 3}, {1, 2}), std::invalid_argument);
}

TEST_CASE("ComputeSpread gives mean, sample sd, min, max over finite values", "[unit]") {
  const Spread s = ComputeSpread({20, 22, 24, NAN});
  CHECK(s.n == 3);
  CHECK(s.mean == Approx(22));
  CHECK(s.stddev == Approx(2));
  CHECK(s.min == 20);
  CHECK(s.max == 24);
  CHECK(ComputeSpread({5}).stddev == 0);
  CHECK(std::isnan(ComputeSpread({NAN}).mean));
}

TEST_CASE("FirstDistanceBelow finds where quality crosses the threshold", "[unit]") {
  CHECK(FirstDistanceBelow({0, 0.1, 0.2, 0.4}, {30, 25, 19, 15}, 20) == Approx(0.2));
  CHECK(std::isnan(FirstDistanceBelow({0, 0.1}, {30, 25}, 20)));
  CHECK(FirstDistanceBelow({0, 0.1}, {NAN, 10}, 20) == Approx(0.1));
}

TEST_CASE("ChooseAutoSize picks the smallest size within the margin of the best", "[unit]") {
  // tiny is 1.5 dB below the best (outside 0.5 dB); small is 0.3 dB below (inside); more is best.
  const std::vector<SizeCandidate> ladder = {{"tiny", 22.5, 1e5, 1e7, 900},
                                             {"small", 23.7, 4e5, 5e7, 400},
                                             {"default", 23.9, 9e5, 2e8, 100},
                                             {"more", 24.0, 4e7, 4e10, 2}};
  AutoSizeChoice c = ChooseAutoSize(ladder, 0.5);
  CHECK(c.index == 1);
  CHECK(c.best_index == 3);
  CHECK(c.best_psnr_db == Approx(24.0));
  CHECK(c.reason.find("'small'") != std::string::npos);
  CHECK(c.reason.find("'more'") != std::string::npos);
  CHECK(c.reason.find("'tiny'") != std::string::npos);  // says why the smaller one lost
  // A wider margin admits tiny; zero margin leaves only the best.
  CHECK(ChooseAutoSize(ladder, 2.0).index == 0);
  CHECK(ChooseAutoSize(ladder, 0.0).index == 3);
  // Unmeasured rungs are ignored; nothing measured -> no choice.
  std::vector<SizeCandidate> partial = ladder;
  partial[1].psnr_db = NAN;
  CHECK(ChooseAutoSize(partial, 0.5).index == 2);
  CHECK(ChooseAutoSize({{"x", NAN, 1, 1, 1}}, 0.5).index == -1);
  CHECK_THROWS_AS(ChooseAutoSize(ladder, -1), std::invalid_argument);
}

TEST_CASE("ChooseAutoSize across methods: without networks the faster one is cheaper", "[unit]") {
  // warp and the fusion blend have no parameters; the refined fusion is best but has a net.
  const std::vector<SizeCandidate> methods = {{"fusion_refined", 25.9, 2e5, 3e8, 30},
                                              {"fusion", 25.7, 0, 0, 40},
                                              {"warp", 25.5, 0, 0, 450},
                                              {"nearest", 19.0, 0, 0, 40000}};
  AutoSizeChoice c = ChooseAutoSize(methods, 0.5, "method");
  CHECK(c.index == 2);  // warp: within 0.4 dB, as cheap as fusion in parameters, 11x faster
  CHECK(c.best_index == 0);
  CHECK(c.reason.find("of the methods within") != std::string::npos);
  CHECK(c.reason.find("'nearest' 19.00 dB") != std::string::npos);  // cheaper, outside
  CHECK(ChooseAutoSize(methods, 0.3, "method").index == 1);  // warp out: the blend
  CHECK(ChooseAutoSize(methods, 0.1, "method").index == 0);  // only the refined one
}
