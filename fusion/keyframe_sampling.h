/// @file keyframe_sampling.h
/// @brief How the `fusion` blend reads a keyframe's colour at a sub-pixel position: bilinear, or
/// bicubic (Keys' cubic convolution, the default, BlendOptions::sampling and ::cubic_a). Both
/// reproduce the image at pixel centres; the bicubic keeps more of the detail between pixels that
/// a bilinear read averages away (at half-pixel offsets a bilinear read halves the amplitude of a
/// one-pixel feature, the bicubic keeps 56 % with a = -0.5, Catmull-Rom, and 59 % with a = -0.75,
/// OpenCV's INTER_CUBIC), so a view resampled from keyframes of its own resolution is less
/// blurred. The bilinear read and Catmull-Rom reproduce linear ramps exactly; a = -0.75 trades
/// that (a ramp read up to ~0.04 px off) for its sharper pass band. Header-only, OpenCV only.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <opencv2/core.hpp>

namespace p2i::fusion {

/// Bilinear RGB sample of a CV_8UC3 image at (x, y) in pixel coordinates, in [0, 1]; the caller
/// guarantees 0 <= x <= w - 1 and 0 <= y <= h - 1.
inline cv::Vec3f SampleBilinear(const cv::Mat& rgb, float x, float y) {
  const int x0 = std::min(static_cast<int>(x), rgb.cols - 2 >= 0 ? rgb.cols - 2 : 0);
  const int y0 = std::min(static_cast<int>(y), rgb.rows - 2 >= 0 ? rgb.rows - 2 : 0);
  const int x1 = std::min(x0 + 1, rgb.cols - 1), y1 = std::min(y0 + 1, rgb.rows - 1);
  const float ax = x - x0, ay = y - y0;
  const cv::Vec3b& p00 = rgb.at<cv::Vec3b>(y0, x0);
  const cv::Vec3b& p01 = rgb.at<cv::Vec3b>(y0, x1);
  const cv::Vec3b& p10 = rgb.at<cv::Vec3b>(y1, x0);
  const cv::Vec3b& p11 = rgb.at<cv::Vec3b>(y1, x1);
  cv::Vec3f out;
  for (int c = 0; c < 3; ++c) {
    const float top = p00[c] + ax * (p01[c] - p00[c]);
    const float bottom = p10[c] + ax * (p11[c] - p10[c]);
    out[c] = (top + ay * (bottom - top)) * (1.0f / 255.0f);
  }
  return out;
}

/// Keys' cubic convolution parameter of Catmull-Rom (exact on linear and quadratic ramps).
constexpr float kCatmullRomA = -0.5f;

/// The four weights of Keys' cubic convolution kernel with parameter `a` (in [-1, 0]; -0.5 is
/// Catmull-Rom) for the taps at -1, 0, 1, 2 of a sample at fraction t in [0, 1) past tap 0. They
/// sum to 1 for every a; t = 0 gives (0, 1, 0, 0).
inline void CubicWeights(float t, float a, float w[4]) {
  const auto near = [a](float x) { return ((a + 2.0f) * x - (a + 3.0f)) * x * x + 1.0f; };
  const auto far = [a](float x) { return ((a * x - 5.0f * a) * x + 8.0f * a) * x - 4.0f * a; };
  w[0] = far(1.0f + t);
  w[1] = near(t);
  w[2] = near(1.0f - t);
  w[3] = far(2.0f - t);
}

/// Bicubic RGB sample (CubicWeights with parameter `a`) of a CV_8UC3 image at (x, y), in [0, 1]
/// (clamped: the cubic overshoots at edges); taps beyond the border repeat the edge pixel. Same
/// domain as SampleBilinear.
inline cv::Vec3f SampleBicubic(const cv::Mat& rgb, float x, float y, float a) {
  const int xi = static_cast<int>(std::floor(x)), yi = static_cast<int>(std::floor(y));
  float wx[4], wy[4];
  CubicWeights(x - static_cast<float>(xi), a, wx);
  CubicWeights(y - static_cast<float>(yi), a, wy);
  float acc[3] = {0.0f, 0.0f, 0.0f};
  if (xi >= 1 && yi >= 1 && xi + 2 < rgb.cols && yi + 2 < rgb.rows) {  // all 16 taps inside
    const size_t step = rgb.step[0];
    const uint8_t* p = rgb.ptr<uint8_t>(yi - 1) + 3 * (xi - 1);
    for (int j = 0; j < 4; ++j, p += step) {
      const float r0 = wx[0] * p[0] + wx[1] * p[3] + wx[2] * p[6] + wx[3] * p[9];
      const float r1 = wx[0] * p[1] + wx[1] * p[4] + wx[2] * p[7] + wx[3] * p[10];
      const float r2 = wx[0] * p[2] + wx[1] * p[5] + wx[2] * p[8] + wx[3] * p[11];
      acc[0] += wy[j] * r0;
      acc[1] += wy[j] * r1;
      acc[2] += wy[j] * r2;
    }
  } else {  // near the border: the taps outside repeat the edge pixel
    int cols[4];
    for (int i = 0; i < 4; ++i) cols[i] = std::clamp(xi - 1 + i, 0, rgb.cols - 1);
    for (int j = 0; j < 4; ++j) {
      const cv::Vec3b* row = rgb.ptr<cv::Vec3b>(std::clamp(yi - 1 + j, 0, rgb.rows - 1));
      float r[3] = {0.0f, 0.0f, 0.0f};
      for (int i = 0; i < 4; ++i) {
        const cv::Vec3b& q = row[cols[i]];
        r[0] += wx[i] * q[0];
        r[1] += wx[i] * q[1];
        r[2] += wx[i] * q[2];
      }
      acc[0] += wy[j] * r[0];
      acc[1] += wy[j] * r[1];
      acc[2] += wy[j] * r[2];
    }
  }
  constexpr float kInv = 1.0f / 255.0f;
  return {std::clamp(acc[0] * kInv, 0.0f, 1.0f), std::clamp(acc[1] * kInv, 0.0f, 1.0f),
          std::clamp(acc[2] * kInv, 0.0f, 1.0f)};
}

}  // namespace p2i::fusion
