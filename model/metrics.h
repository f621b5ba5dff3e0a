/// @file metrics.h
/// @brief Image and depth quality metrics (PSNR, SSIM, AbsRel, RMSE) and a latency recorder for
/// speed figures. Torch-free: nodes, tools and benches include it directly.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace p2i::model {

/// PSNR of identical images is infinite; we report this cap instead so that means over views
/// stay finite (it corresponds to MSE = 1e-10 on [0, 1] images, far below 8-bit quantisation).
constexpr double kPsnrCapDb = 100.0;

/// Converts an RGB (or grey) image to CV_64FC<n> in [0, 1]: CV_8U is divided by 255, CV_16U by
/// 65535, float/double are taken as already in [0, 1]. Throws std::invalid_argument on an empty
/// image or another depth.
cv::Mat ToUnitFloat(const cv::Mat& image);

/// Peak signal-to-noise ratio in dB with peak 1: 10 log10(1 / MSE), MSE over all pixels AND
/// channels (one MSE for the whole image, not a mean of per-channel PSNRs). Inputs: same size and
/// channel count, CV_8U (scaled by 1/255) or float in [0, 1]. Capped at kPsnrCapDb. Throws
/// std::invalid_argument when sizes/channels differ.
double Psnr(const cv::Mat& a, const cv::Mat& b);

/// Structural similarity (Wang et al. 2004) on [0, 1] images: 11x11 Gaussian window, sigma 1.5,
/// C1 = (0.01)^2, C2 = (0.03)^2 (peak 1). Local statistics are computed with "same"-size
/// filtering (OpenCV's default border, reflect-101), so the SSIM map covers every pixel. The
/// score is the mean of the SSIM map over all pixels of each channel, then the plain mean over
/// the channels (R, G, B weighted equally; no conversion to luma). This matches OpenCV contrib's
/// cv::quality::QualitySSIM on the same data scaled to [0, 255]. Throws like Psnr.
double Ssim(const cv::Mat& a, const cv::Mat& b);

/// Depth errors over the pixels valid in BOTH maps (finite and > 0; 0 = invalid).
struct DepthErrors {
  double abs_rel = 0.0;         ///< mean |pred - gt| / gt
  double rmse_m = 0.0;          ///< sqrt(mean (pred - gt)^2), metres
  double valid_fraction = 0.0;  ///< valid_pixels / gt_valid_pixels (how much of the measurable
                                ///< depth the method predicted); 0 when gt has no valid pixel
  int64_t valid_pixels = 0;     ///< pixels valid in both
  int64_t gt_valid_pixels = 0;  ///< pixels valid in the ground truth
  int64_t total_pixels = 0;
};

/// Both CV_32FC1 (metres) of the same size; throws std::invalid_argument otherwise. With no pixel
/// valid in both, abs_rel and rmse_m are NaN (a metric that does not exist, not a perfect one).
DepthErrors ComputeDepthErrors(const cv::Mat& predicted, const cv::Mat& ground_truth);

/// Summary of a latency recorder. Percentiles use the nearest-rank rule on sorted samples:
/// p-th percentile = sorted[ceil(p/100 * n) - 1].
struct LatencySummary {
  int64_t count = 0;
  double views_per_second = 0.0;  ///< count / total time (batch 1: one view per sample)
  double mean_ms = 0.0;
  double p50_ms = 0.0;
  double p99_ms = 0.0;
  double min_ms = 0.0;
  double max_ms = 0.0;
  int threads = 0;                ///< thread count the samples were measured with (as stated)
};

/// Records per-view latencies (batch 1) and summarises them. Not thread-safe: one recorder per
/// measuring thread. The recorder does not time anything itself: wrap the call with
/// Start()/Stop() or pass measured durations to Add().
class LatencyRecorder {
 public:
  /// `threads`: the intra-op thread count in use, reported with the figures.
  explicit LatencyRecorder(int threads = 1) : threads_(threads) {}

  void Start();
  /// Ends the interval opened by Start() and records it; throws std::logic_error without Start().
  void Stop();
  /// Records one latency in seconds (>= 0, finite; else std::invalid_argument).
  void Add(double seconds);
  void Clear() { samples_s_.clear(); }

  int64_t Count() const { return static_cast<int64_t>(samples_s_.size()); }
  const std::vector<double>& SamplesSeconds() const { return samples_s_; }
  /// Nearest-rank percentile in milliseconds, p in [0, 100]; throws std::logic_error when empty.
  double PercentileMs(double p) const;
  /// All zeros (count 0) when empty.
  LatencySummary Summary() const;

 private:
  int threads_;
  std::vector<double> samples_s_;
  int64_t start_ns_ = -1;
};

}  // namespace p2i::model
