/// @file keyframe_pyramid.h
/// @brief Pre-filtered, smaller copies of a keyframe's colour (a pyramid of 2x2 means) and the level a
/// view reads from. A view rendered at a fraction of the camera's resolution (e.g. 128x128 or
/// 320x240 from a 640x480 camera) that read the full-resolution keyframes would sample them
/// several pixels apart without a low-pass first: aliasing (texture detail turning into noise
/// that changes from view to view) and a cache miss per read. Reading the level whose focal
/// length is the nearest at or above the view's keeps every read at about one keyframe pixel per
/// view pixel. A view at the camera's own resolution reads level 0, the keyframe itself.
/// Header-only, OpenCV only.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace p2i::fusion {

/// Levels 1.. of `rgb`'s pyramid, each the mean of 2x2 pixels of the one before (cv::INTER_AREA
/// at scale 1/2: the box filter a camera's pixels integrate over, and the one the camera node's
/// area resize applies), at most `max_levels`, stopping before a side would fall under 8 pixels.
/// Level 0 (the image itself) is not included.
inline std::vector<cv::Mat> ColourPyramid(const cv::Mat& rgb, int max_levels) {
  std::vector<cv::Mat> levels;
  cv::Mat cur = rgb;
  for (int l = 1; l <= max_levels; ++l) {
    if (cur.cols / 2 < 8 || cur.rows / 2 < 8) break;
    cv::Mat next;
    cv::resize(cur, next, cv::Size(cur.cols / 2, cur.rows / 2), 0, 0, cv::INTER_AREA);
    levels.push_back(next);
    cur = next;
  }
  return levels;
}

/// Levels 1.. of `depth`'s (CV_32FC1, 0 = invalid) pyramid for the visibility test, the same
/// sizes as ColourPyramid's: each pixel the nearest valid depth of the 2x2 pixels under it (0
/// when none is valid). A view at level L then tests a point against 1 value where it would read
/// 1 of 4^L pixels of a far larger map: a cache miss per read at 640x480 (the load stall was 28 %
/// of the blend's own time at 128x128). The nearest of the block, not a mean: a mean across a
/// depth edge is a depth no surface has, and the nearest keeps a point behind an edge hidden.
inline std::vector<cv::Mat> DepthPyramid(const cv::Mat& depth, int max_levels) {
  std::vector<cv::Mat> levels;
  cv::Mat cur = depth;
  for (int l = 1; l <= max_levels; ++l) {
    if (cur.cols / 2 < 8 || cur.rows / 2 < 8) break;
    cv::Mat next(cur.rows / 2, cur.cols / 2, CV_32FC1);
    for (int y = 0; y < next.rows; ++y) {
      const float* a = cur.ptr<float>(2 * y);
      const float* b = cur.ptr<float>(2 * y + 1);
      float* out = next.ptr<float>(y);
      for (int x = 0; x < next.cols; ++x) {
        float best = 0.0f;
        for (const float d : {a[2 * x], a[2 * x + 1], b[2 * x], b[2 * x + 1]})
          if (d > 0.0f && (best == 0.0f || d < best)) best = d;
        out[x] = best;
      }
    }
    levels.push_back(next);
    cur = next;
  }
  return levels;
}

/// The pyramid level a view with focal lengths (fx, fy) reads from keyframes with (kfx, kfy):
/// the largest L with kf / 2^L >= f on both axes (so a read never magnifies a level), capped at
/// `max_level`. 0 when the view is at or above the keyframes' resolution.
inline int PyramidLevelFor(double fx, double fy, double kfx, double kfy, int max_level) {
  const double ratio = std::min(kfx / fx, kfy / fy);
  if (!(ratio >= 2.0)) return 0;
  const int level = static_cast<int>(std::floor(std::log2(ratio) + 1e-9));
  return std::clamp(level, 0, std::max(0, max_level));
}

/// Whether a view reading pyramid `level` should read it with the bicubic kernel under
/// sampling "auto": what is left of the view's focal ratio after the level's halvings (in
/// [1, 2) when the view is below the keyframes' resolution, 1 when the level matches it) is
/// under sqrt(2), the middle of the octave. Above that the view skips level pixels, and the
/// Catmull-Rom kernel, narrower than a pixel of the view, keeps detail the camera's area filter
/// removes (aliasing): at 128x128 from 640x480 keyframes (ratio 3.75: level 1, 1.875 left) the
/// bilinear read scored 35.89 / 0.978 against the camera's frame, the bicubic 33.99 / 0.969.
inline bool UseBicubicRead(double fx, double fy, double kfx, double kfy, int level) {
  const double left = std::min(kfx / fx, kfy / fy) / static_cast<double>(1 << level);
  return left < std::sqrt(2.0);
}

/// A keyframe pixel coordinate (x, y) at level 0 expressed at `level` (pixel centres at integers:
/// x_L = (x + 0.5) / 2^L - 0.5), clamped to the level's [0, w - 1] x [0, h - 1].
inline void ToPyramidLevel(int level, int w, int h, float* x, float* y) {
  if (level == 0) return;
  const float s = 1.0f / static_cast<float>(1 << level);
  *x = std::clamp((*x + 0.5f) * s - 0.5f, 0.0f, static_cast<float>(w - 1));
  *y = std::clamp((*y + 0.5f) * s - 0.5f, 0.0f, static_cast<float>(h - 1));
}

}  // namespace p2i::fusion
