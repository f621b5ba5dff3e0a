/// @file stats.h
/// @brief Small statistics for `p2i bench`: mean/spread, Spearman rank correlation, the Pareto
/// front of (speed, quality) points and the --auto-size choice. Pure functions, no I/O.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace p2i::eval {

/// Mean, sample standard deviation (n - 1; 0 for n = 1), min, max, n over the finite values.
/// All NaN when no value is finite (n = 0).
struct Spread {
  double mean = 0.0;
  double stddev = 0.0;
  double min = 0.0;
  double max = 0.0;
  size_t n = 0;
};
Spread ComputeSpread(const std::vector<double>& values);

/// Ranks 1..n with ties given the average of the ranks they span (fractional ranking).
std::vector<double> FractionalRanks(const std::vector<double>& values);

/// Spearman's rho: the Pearson correlation of the fractional ranks of x and y, over the pairs
/// where both are finite. NaN with fewer than 3 such pairs or when either side is constant.
/// Throws std::invalid_argument when x and y differ in length.
double SpearmanRho(const std::vector<double>& x, const std::vector<double>& y);

/// A point of a speed/quality chart.
struct ParetoPoint {
  double x = 0.0;  ///< e.g. views/s
  double y = 0.0;  ///< e.g. PSNR or LPIPS-Squeeze
};

/// Indices (ascending) of the non-dominated points: no other point is at least as good on both
/// axes and strictly better on one. `maximize_x` / `maximize_y` say which direction is better
/// (PSNR: maximise; LPIPS: minimise). Points with a non-finite coordinate are never on the
/// front and never dominate. Duplicate points are all kept.
std::vector<size_t> ParetoFront(const std::vector<ParetoPoint>& points, bool maximize_x,
                                bool maximize_y);

/// One rung of a model-size ladder with its measured figures.
struct SizeCandidate {
  std::string name;
  double psnr_db = 0.0;      ///< quality (mean over seeds/views); NaN = not measured
  double params = 0.0;       ///< parameter count
  double flops = 0.0;        ///< FLOPs per view
  double views_per_s = 0.0;
};

/// The --auto-size choice: the cheapest candidate (fewest parameters, then fewest FLOPs, then
/// most views/s, then ladder order) whose PSNR is within `margin_db` of the best PSNR of the
/// ladder. Methods without a network (warp, the fusion blend) have 0 parameters and FLOPs, so
/// among them the faster one is cheaper.
struct AutoSizeChoice {
  int index = -1;        ///< into the candidates; -1 when none has a finite PSNR
  int best_index = -1;   ///< the candidate with the best PSNR
  double best_psnr_db = 0.0;
  std::string reason;    ///< one paragraph saying why (printed by `p2i bench --auto-size`)
};
/// Throws std::invalid_argument for a negative or non-finite margin.
/// `noun` names the candidates in the reason ("size" on a size ladder, "method" across methods).
AutoSizeChoice ChooseAutoSize(const std::vector<SizeCandidate>& candidates, double margin_db,
                              const std::string& noun = "size");

/// The first sweep distance at which `quality` falls below `threshold` (distances ascending,
/// quality[i] measured at distances[i]); NaN when it never does. Non-finite qualities are
/// skipped.
double FirstDistanceBelow(const std::vector<double>& distances, const std::vector<double>& quality,
                          double threshold);

}  // namespace p2i::eval
