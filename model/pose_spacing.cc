/// @file pose_spacing.cc
/// @brief MedianNeighbourDistance and FourierBandsForSpacing.
#include "model/pose_spacing.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace p2i::model {

double MedianNeighbourDistance(const std::vector<std::array<float, 7>>& inputs) {
  constexpr double kSame = 1e-9;
  std::vector<double> nearest;
  nearest.reserve(inputs.size());
  for (size_t i = 0; i < inputs.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < inputs.size(); ++j) {
      if (j == i) continue;
      double d2 = 0;
      for (int a = 0; a < 7; ++a) {
        const double d = static_cast<double>(inputs[i][a]) - inputs[j][a];
        d2 += d * d;
      }
      const double d = std::sqrt(d2);
      if (d > kSame) best = std::min(best, d);
    }
    if (std::isfinite(best)) nearest.push_back(best);
  }
  if (nearest.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t mid = nearest.size() / 2;
  std::nth_element(nearest.begin(), nearest.begin() + mid, nearest.end());
  if (nearest.size() % 2 == 1) return nearest[mid];
  const double upper = nearest[mid];
  const double lower = *std::max_element(nearest.begin(), nearest.begin() + mid);
  return 0.5 * (lower + upper);
}

int FourierBandsForSpacing(double spacing) {
  if (!(std::isfinite(spacing) && spacing > 0))
    throw std::invalid_argument(
        "fourier_bands: auto needs the training poses' median neighbour distance to be finite "
        "and positive, got " + std::to_string(spacing) +
        " (fewer than two distinct training poses?): set fourier_bands to a number instead");
  const double bands = 1.0 + std::log2(2.0 / (kAutoBandsPeriodRatio * spacing));
  return static_cast<int>(std::clamp<long>(std::lround(bands), 1L, 16L));
}

}  // namespace p2i::model
