/// @file fast_angle.h
/// @brief The angle between two directions from |cross| and dot, without libm's atan2: the
/// keyframe blend takes one per pixel and slot, and std::atan2 was ~30 % of the blend's time
/// (perf, fusion_bench --row). Max error 2e-5 rad (1e-3 degrees, float rounding included; tests/fusion/fast_angle_test.cc).
#pragma once

#include <algorithm>
#include <cmath>

namespace p2i::fusion {

/// atan2(s, c) for s >= 0 (the sine side of an angle in [0, pi]): a polynomial of atan on [0, 1]
/// with the octant folded in. Returns 0 when both are 0.
inline float AngleFromSinCos(float s, float c) {
  const float ac = std::fabs(c);
  const float hi = std::max(ac, s), lo = std::min(ac, s);
  if (!(hi > 0.0f)) return 0.0f;
  const float t = lo / hi, t2 = t * t;
  // Abramowitz & Stegun 4.4.49: |error| <= 1e-5 on [0, 1].
  float r = t * (0.9998660f + t2 * (-0.3302995f + t2 * (0.1801410f + t2 * (-0.0851330f + t2 * 0.0208351f))));
  if (s > ac) r = 1.57079637f - r;
  if (c < 0.0f) r = 3.14159274f - r;
  return r;
}

}  // namespace p2i::fusion
