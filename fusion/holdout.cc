/// @file holdout.cc
/// @brief The held-out keyframes of a fusion scene's leave-one-out checks (holdout.h).
#include "fusion/holdout.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "fusion/fusion_scene.h"

namespace p2i::fusion {

Holdouts PickHoldouts(const FusionScene& scene, int max_frames, int max_width, const char* who) {
  if (max_frames < 1) throw std::invalid_argument(std::string(who) + ": max_frames must be >= 1");
  if (max_width < 8) throw std::invalid_argument(std::string(who) + ": max_width must be >= 8");
  Holdouts out;
  const scene::CameraInfo& full = scene.frame_camera();
  const int w = std::min(full.image_width, max_width);
  const int h = std::max(1, static_cast<int>(std::lround(full.image_height * static_cast<double>(w) /
                                                         full.image_width)));
  out.camera = w == full.image_width ? full : full.Scaled(w, h);
  const int n = static_cast<int>(scene.keyframes().size());
  if (n < 3) return out;
  const int m = std::min(n, max_frames);
  for (int k = 0; k < m; ++k) out.indices.push_back(std::min(n - 1, static_cast<int>((k + 0.5) * n / m)));
  return out;
}

cv::Mat ResizedTo(const cv::Mat& image, const scene::CameraInfo& camera, int interpolation) {
  if (image.cols == camera.image_width && image.rows == camera.image_height) return image;
  cv::Mat out;
  cv::resize(image, out, cv::Size(camera.image_width, camera.image_height), 0.0, 0.0, interpolation);
  return out;
}

}  // namespace p2i::fusion
