/// @file push_pull_fill.cc
/// @brief Push-pull hole filling.
#include "model/push_pull_fill.h"

#include <vector>

#include <opencv2/imgproc.hpp>

namespace p2i::model {

void PushPullFill(cv::Mat& image, const cv::Mat& valid) {
  cv::Mat weight;
  const cv::Mat keep = valid != 0;  // 255 where valid
  keep.convertTo(weight, CV_32F, 1.0 / 255.0);
  std::vector<cv::Mat> premult{image.mul(weight)}, weights{weight};
  while (premult.back().cols > 1 || premult.back().rows > 1) {
    const cv::Size next((premult.back().cols + 1) / 2, (premult.back().rows + 1) / 2);
    cv::Mat p, w;
    cv::resize(premult.back(), p, next, 0, 0, cv::INTER_AREA);
    cv::resize(weights.back(), w, next, 0, 0, cv::INTER_AREA);
    premult.push_back(p);
    weights.push_back(w);
  }
  // Top level: normalised average of everything valid.
  cv::Mat filled;
  cv::divide(premult.back(), cv::max(weights.back(), 1e-12), filled);
  for (int l = static_cast<int>(premult.size()) - 2; l >= 0; --l) {
    cv::Mat up;
    cv::resize(filled, up, premult[static_cast<size_t>(l)].size(), 0, 0, cv::INTER_LINEAR);
    cv::Mat level;
    cv::divide(premult[static_cast<size_t>(l)], cv::max(weights[static_cast<size_t>(l)], 1e-12),
               level);
    // Where a level has (partial) valid support keep its own average, blended by its weight.
    const cv::Mat& w = weights[static_cast<size_t>(l)];
    cv::Mat wc = cv::min(w, 1.0);
    cv::Mat one_minus = 1.0 - wc;
    filled = level.mul(wc) + up.mul(one_minus);
  }
  filled.copyTo(image, ~keep);
}

void PushPullFillRgbd(cv::Mat& rgb, cv::Mat& depth, const cv::Mat& valid) {
  const int n_valid = cv::countNonZero(valid);
  if (n_valid == 0 || n_valid == valid.rows * valid.cols) return;
  cv::Mat rgb_f;
  rgb.convertTo(rgb_f, CV_32FC3);
  std::vector<cv::Mat> channels;
  cv::split(rgb_f, channels);
  for (auto& ch : channels) PushPullFill(ch, valid);
  cv::merge(channels, rgb_f);
  rgb_f.convertTo(rgb, CV_8UC3);
  PushPullFill(depth, valid);
}

}  // namespace p2i::model
