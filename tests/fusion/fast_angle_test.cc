/// @file fast_angle_test.cc
/// @brief AngleFromSinCos agrees with std::atan2 to 2e-5 rad over [0, pi] and at any scale.
#include <cmath>

#include <catch2/catch.hpp>

#include "fusion/fast_angle.h"

namespace p2i::fusion {
namespace {

TEST_CASE("AngleFromSinCos: within 2e-5 rad of atan2 over [0, pi], at any length", "[unit]") {
  double worst = 0.0;
  for (int i = 0; i <= 100000; ++i) {
    const double a = M_PI * i / 100000.0;
    for (double len : {1e-3, 1.0, 37.0}) {
      const float s = static_cast<float>(len * std::sin(a)), c = static_cast<float>(len * std::cos(a));
      worst = std::max(worst, std::abs(double(AngleFromSinCos(s, c)) - std::atan2(double(s), double(c))));
    }
  }
  CHECK(worst < 2e-5);
  CHECK(AngleFromSinCos(0.0f, 1.0f) == 0.0f);
  CHECK(AngleFromSinCos(1.0f, 0.0f) == Approx(M_PI / 2).margin(1e-6));
  CHECK(AngleFromSinCos(0.0f, -2.0f) == Approx(M_PI).margin(1e-6));
  CHECK(AngleFromSinCos(0.0f, 0.0f) == 0.0f);
}

}  // namespace
}  // namespace p2i::fusion
