/// @file metrics.cc
/// @brief PSNR, SSIM, depth errors and the latency recorder.
#include "model/metrics.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "util/order_stats.h"

namespace p2i::model {
namespace {

void CheckPair(const cv::Mat& a, const cv::Mat& b, const char* what) {
  if (a.empty() || b.empty()) {
    throw std::invalid_argument(std::string(what) + ": empty image");
  }
  if (a.size() != b.size() || a.channels() != b.channels()) {
    throw std::invalid_argument(std::string(what) + ": images differ in size or channels (" +
                                std::to_string(a.cols) + "x" + std::to_string(a.rows) + "x" +
                                std::to_string(a.channels()) + " vs " + std::to_string(b.cols) +
                                "x" + std::to_string(b.rows) + "x" +
                                std::to_string(b.channels()) + ")");
  }
}

/// Mean of the SSIM map of one CV_64FC1 channel in [0, 1].
double SsimChannel(const cv::Mat& x, const cv::Mat& y) {
  constexpr double kC1 = 0.01 * 0.01;
  constexpr double kC2 = 0.03 * 0.03;
  const cv::Size kWindow(11, 11);
  constexpr double kSigma = 1.5;
  cv::Mat mu_x, mu_y, xx, yy, xy;
  cv::GaussianBlur(x, mu_x, kWindow, kSigma);
  cv::GaussianBlur(y, mu_y, kWindow, kSigma);
  cv::GaussianBlur(x.mul(x), xx, kWindow, kSigma);
  cv::GaussianBlur(y.mul(y), yy, kWindow, kSigma);
  cv::GaussianBlur(x.mul(y), xy, kWindow, kSigma);
  const cv::Mat mu_xx = mu_x.mul(mu_x);
  const cv::Mat mu_yy = mu_y.mul(mu_y);
  const cv::Mat mu_xy = mu_x.mul(mu_y);
  const cv::Mat sigma_xx = xx - mu_xx;
  const cv::Mat sigma_yy = yy - mu_yy;
  const cv::Mat sigma_xy = xy - mu_xy;
  const cv::Mat num = (2.0 * mu_xy + kC1).mul(2.0 * sigma_xy + kC2);
  const cv::Mat den = (mu_xx + mu_yy + kC1).mul(sigma_xx + sigma_yy + kC2);
  cv::Mat map;
  cv::divide(num, den, map);
  return cv::mean(map)[0];
}

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

cv::Mat ToUnitFloat(const cv::Mat& image) {
  if (image.empty()) throw std::invalid_argument("ToUnitFloat: empty image");
  cv::Mat out;
  switch (image.depth()) {
    case CV_8U:
      image.convertTo(out, CV_64F, 1.0 / 255.0);
      break;
    case CV_16U:
      image.convertTo(out, CV_64F, 1.0 / 65535.0);
      break;
    case CV_32F:
    case CV_64F:
      image.convertTo(out, CV_64F);
      break;
    default:
      throw std::invalid_argument(
          "ToUnitFloat: unsupported image depth (use CV_8U, CV_16U, CV_32F or CV_64F)");
  }
  return out;
}

double Psnr(const cv::Mat& a, const cv::Mat& b) {
  CheckPair(a, b, "Psnr");
  cv::Mat diff = ToUnitFloat(a) - ToUnitFloat(b);
  const double sse = diff.dot(diff);
  const double mse = sse / static_cast<double>(diff.total() * diff.channels());
  if (mse <= 0.0) return kPsnrCapDb;
  return std::min(kPsnrCapDb, 10.0 * std::log10(1.0 / mse));
}

double Ssim(const cv::Mat& a, const cv::Mat& b) {
  CheckPair(a, b, "Ssim");
  // Channels are processed one at a time: OpenCV's MatExpr scalar arithmetic on multi-channel
  // arrays is not guaranteed to broadcast, so constants are applied to single-channel maps.
  std::vector<cv::Mat> xs, ys;
  cv::split(ToUnitFloat(a), xs);
  cv::split(ToUnitFloat(b), ys);
  double sum = 0.0;
  for (size_t c = 0; c < xs.size(); ++c) sum += SsimChannel(xs[c], ys[c]);
  return sum / static_cast<double>(xs.size());
}

DepthErrors ComputeDepthErrors(const cv::Mat& predicted, const cv::Mat& ground_truth) {
  if (predicted.type() != CV_32FC1 || ground_truth.type() != CV_32FC1 ||
      predicted.size() != ground_truth.size()) {
    throw std::invalid_argument(
        "ComputeDepthErrors: both depth maps must be CV_32FC1 (metres) of the same size");
  }
  DepthErrors e;
  e.total_pixels = static_cast<int64_t>(ground_truth.total());
  double sum_rel = 0.0;
  double sum_sq = 0.0;
  for (int r = 0; r < ground_truth.rows; ++r) {
    const float* p = predicted.ptr<float>(r);
    const float* g = ground_truth.ptr<float>(r);
    for (int c = 0; c < ground_truth.cols; ++c) {
      const bool gt_ok = std::isfinite(g[c]) && g[c] > 0.0f;
      if (!gt_ok) continue;
      ++e.gt_valid_pixels;
      if (!(std::isfinite(p[c]) && p[c] > 0.0f)) continue;
      ++e.valid_pixels;
      const double d = static_cast<double>(p[c]) - static_cast<double>(g[c]);
      sum_rel += std::abs(d) / g[c];
      sum_sq += d * d;
    }
  }
  if (e.valid_pixels == 0) {
    e.abs_rel = std::numeric_limits<double>::quiet_NaN();
    e.rmse_m = std::numeric_limits<double>::quiet_NaN();
  } else {
    e.abs_rel = sum_rel / static_cast<double>(e.valid_pixels);
    e.rmse_m = std::sqrt(sum_sq / static_cast<double>(e.valid_pixels));
  }
  e.valid_fraction = e.gt_valid_pixels > 0 ? static_cast<double>(e.valid_pixels) /
                                                 static_cast<double>(e.gt_valid_pixels)
                                           : 0.0;
  return e;
}

void LatencyRecorder::Start() { start_ns_ = NowNs(); }

void LatencyRecorder::Stop() {
  if (start_ns_ < 0) throw std::logic_error("LatencyRecorder::Stop without Start");
  Add(static_cast<double>(NowNs() - start_ns_) * 1e-9);
  start_ns_ = -1;
}

void LatencyRecorder::Add(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) {
    throw std::invalid_argument("LatencyRecorder::Add: latency must be finite and >= 0, got " +
                                std::to_string(seconds));
  }
  samples_s_.push_back(seconds);
}

double LatencyRecorder::PercentileMs(double p) const {
  if (samples_s_.empty()) throw std::logic_error("LatencyRecorder::PercentileMs: no samples");
  if (!(p >= 0.0 && p <= 100.0)) {
    throw std::invalid_argument("LatencyRecorder::PercentileMs: p must be in [0, 100]");
  }
  return util::PercentileNearestRank(samples_s_, p) * 1e3;
}

LatencySummary LatencyRecorder::Summary() const {
  LatencySummary s;
  s.threads = threads_;
  if (samples_s_.empty()) return s;
  s.count = Count();
  const double total = std::accumulate(samples_s_.begin(), samples_s_.end(), 0.0);
  s.views_per_second = total > 0.0 ? static_cast<double>(s.count) / total
                                   : std::numeric_limits<double>::infinity();
  s.mean_ms = total / static_cast<double>(s.count) * 1e3;
  s.p50_ms = PercentileMs(50.0);
  s.p99_ms = PercentileMs(99.0);
  s.min_ms = *std::min_element(samples_s_.begin(), samples_s_.end()) * 1e3;
  s.max_ms = *std::max_element(samples_s_.begin(), samples_s_.end()) * 1e3;
  return s;
}

}  // namespace p2i::model
