/// @file pose_dependence.cc
/// @brief PoseDependence: per-pixel standard deviation of outputs vs ground truth over poses.
#include "model/pose_dependence.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace p2i::model {
namespace {

cv::Mat ToDouble(const cv::Mat& m) {
  cv::Mat out;
  m.convertTo(out, CV_MAKETYPE(CV_64F, m.channels()));
  return out;
}

double MeanStd(const cv::Mat& sum, const cv::Mat& sq, int64_t n) {
  if (n < 2) return std::nan("");
  const double k = static_cast<double>(n);
  cv::Mat var = sq / k - (sum / k).mul(sum / k);
  cv::max(var, 0.0, var);
  cv::Mat sd;
  cv::sqrt(var.reshape(1), sd);
  return cv::mean(sd)[0];
}

}  // namespace

void PoseDependence::Add(const cv::Mat& output, const cv::Mat& truth) {
  if (output.empty() || truth.empty())
    throw std::invalid_argument("PoseDependence::Add: empty image");
  if (output.size() != truth.size() || output.channels() != truth.channels())
    throw std::invalid_argument("PoseDependence::Add: output and ground truth differ in size or "
                                "channels; resize the output to the ground truth first");
  if (!sum_out_.empty() && (output.size() != sum_out_.size() ||
                            output.channels() != sum_out_.channels()))
    throw std::invalid_argument("PoseDependence::Add: every pair must have the size of the first");
  const cv::Mat o = ToDouble(output), g = ToDouble(truth);
  if (sum_out_.empty()) {
    sum_out_ = cv::Mat::zeros(o.size(), o.type());
    sq_out_ = sum_out_.clone();
    sum_gt_ = sum_out_.clone();
    sq_gt_ = sum_out_.clone();
  }
  sum_out_ += o;
  sq_out_ += o.mul(o);
  sum_gt_ += g;
  sq_gt_ += g.mul(g);
  ++count_;
}

double PoseDependence::OutputStd() const { return MeanStd(sum_out_, sq_out_, count_); }
double PoseDependence::TruthStd() const { return MeanStd(sum_gt_, sq_gt_, count_); }

double PoseDependence::Score() const {
  const double gt = TruthStd();
  if (!(gt > 1e-12)) return std::nan("");
  return OutputStd() / gt;
}

std::string PoseDependenceWarning(double score) {
  if (!(score < kPoseDependenceWarn)) return "";
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "WARNING: pose-dependence %.2f < %.2f: the model renders nearly the same image for "
                "every pose (collapsed); its PSNR is not evidence of learning",
                score, kPoseDependenceWarn);
  return buf;
}

}  // namespace p2i::model
