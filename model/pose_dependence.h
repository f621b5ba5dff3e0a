/// @file pose_dependence.h
/// @brief The pose-dependence score: does a model render a different image for every pose, as
/// the scene does, or one image for every pose (collapse)? Torch-free (trainer, `p2i export`,
/// `p2i bench`, the trainer node).
///
/// Score = mean over pixels and channels of the per-pixel standard deviation of the model's
/// outputs over a fixed set of poses, divided by the same of the ground truth at those poses:
/// 1 = the output varies as much as the scene does, 0 = the same image for every pose. It
/// measures variation only, not correctness (a model rendering noise also varies): read it
/// beside PSNR/SSIM. Below kPoseDependenceWarn the run is reported as collapsed.
#pragma once

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace p2i::model {

/// Below this the model counts as collapsed (docs/MODEL.md "Pose-dependence score").
constexpr double kPoseDependenceWarn = 0.5;

/// Accumulates (output, ground truth) pairs of the same pose; O(pixels) memory. Not
/// thread-safe.
class PoseDependence {
 public:
  /// `output` and `truth`: same size and channel count, CV_8U (any channels) or CV_32F; every
  /// pair of one accumulator the same size. Throws std::invalid_argument otherwise.
  void Add(const cv::Mat& output, const cv::Mat& truth);
  int64_t Count() const { return count_; }
  /// Mean per-pixel std of the outputs / of the ground truth; NaN with fewer than 2 pairs or a
  /// ground truth that never changes.
  double Score() const;
  double OutputStd() const;  ///< mean per-pixel std of the outputs (input units)
  double TruthStd() const;   ///< the same for the ground truth

 private:
  cv::Mat sum_out_, sq_out_, sum_gt_, sq_gt_;  // CV_64FC(n)
  int64_t count_ = 0;
};

/// "" when `score` >= kPoseDependenceWarn or NaN; else a one-line warning naming the score and
/// the threshold ("pose-dependence 0.12 < 0.5: the model renders nearly the same image ...").
std::string PoseDependenceWarning(double score);

}  // namespace p2i::model
