/// @file metrics_test.cc
/// @brief PSNR/SSIM against hand-computed values and OpenCV contrib's quality module; depth
/// errors and latency percentiles on hand-made data.
#include <cmath>

#include <catch2/catch.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/quality.hpp>

#include "model/metrics.h"

using namespace p2i::model;

namespace {

cv::Mat Textured(int w, int h, uint64_t seed) {
  cv::Mat img(h, w, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(img, img, cv::Size(5, 5), 1.2);  // some spatial structure
  return img;
}

}  // namespace

TEST_CASE("Psnr matches hand-computed values", "[unit]") {
  cv::Mat a(8, 8, CV_32FC3, cv::Scalar(0.2, 0.2, 0.2));
  cv::Mat b(8, 8, CV_32FC3, cv::Scalar(0.3, 0.3, 0.3));
  CHECK(Psnr(a, b) == Approx(20.0).margin(1e-6));  // MSE 0.01
  // One channel off by 0.3: MSE = 0.09 / 3 = 0.03 over all channels.
  cv::Mat c(8, 8, CV_32FC3, cv::Scalar(0.2, 0.2, 0.5));
  CHECK(Psnr(a, c) == Approx(10.0 * std::log10(1.0 / 0.03)).margin(1e-5));
  CHECK(Psnr(a, a) == kPsnrCapDb);
  // 8-bit input is scaled by 1/255.
  cv::Mat d(4, 4, CV_8UC3, cv::Scalar(0, 0, 0));
  cv::Mat e(4, 4, CV_8UC3, cv::Scalar(51, 51, 51));  // 0.2
  CHECK(Psnr(d, e) == Approx(10.0 * std::log10(1.0 / 0.04)).margin(1e-9));
  CHECK_THROWS_AS(Psnr(a, cv::Mat(4, 8, CV_32FC3)), std::invalid_argument);
}

TEST_CASE("Psnr agrees with cv::quality::QualityMSE", "[unit]") {
  const cv::Mat a = Textured(64, 48, 1);
  const cv::Mat b = Textured(64, 48, 2);
  const cv::Scalar mse = cv::quality::QualityMSE::compute(a, b, cv::noArray());
  const double mse_unit = (mse[0] + mse[1] + mse[2]) / 3.0 / (255.0 * 255.0);
  CHECK(Psnr(a, b) == Approx(10.0 * std::log10(1.0 / mse_unit)).epsilon(1e-9));
  // Single-channel PSNR also agrees with QualityPSNR (peak 255).
  cv::Mat ga, gb;
  cv::cvtColor(a, ga, cv::COLOR_RGB2GRAY);
  cv::cvtColor(b, gb, cv::COLOR_RGB2GRAY);
  const cv::Scalar ref = cv::quality::QualityPSNR::compute(ga, gb, cv::noArray());
  CHECK(Psnr(ga, gb) == Approx(ref[0]).epsilon(1e-9));
}

TEST_CASE("Ssim of constant images matches the closed form", "[unit]") {
  // Constant images: all variances are 0, so SSIM = (2 mx my + C1) / (mx^2 + my^2 + C1).
  cv::Mat a(20, 20, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5));
  cv::Mat b(20, 20, CV_32FC3, cv::Scalar(0.25, 0.25, 0.25));
  const double c1 = 1e-4;
  const double expected = (2 * 0.5 * 0.25 + c1) / (0.25 + 0.0625 + c1);
  CHECK(Ssim(a, b) == Approx(expected).epsilon(1e-9));
  // Different per channel: the score is the plain mean over channels.
  cv::Mat c(20, 20, CV_32FC3, cv::Scalar(0.5, 0.25, 1.0));
  const double e1 = (2 * 0.5 * 0.5 + c1) / (0.25 + 0.25 + c1);
  const double e2 = (2 * 0.5 * 0.25 + c1) / (0.25 + 0.0625 + c1);
  const double e3 = (2 * 0.5 * 1.0 + c1) / (0.25 + 1.0 + c1);
  CHECK(Ssim(a, c) == Approx((e1 + e2 + e3) / 3.0).epsilon(1e-9));
  CHECK(Ssim(a, a) == Approx(1.0).epsilon(1e-12));
}

TEST_CASE("Ssim agrees with cv::quality::QualitySSIM", "[unit]") {
  const cv::Mat a = Textured(80, 60, 3);
  cv::Mat noise(a.size(), CV_8UC3);
  cv::RNG(4).fill(noise, cv::RNG::NORMAL, 0, 20);
  cv::Mat b;
  cv::add(a, noise, b, cv::noArray(), CV_8UC3);
  // QualitySSIM hard-codes the constants for peak 255: feed it the same data on [0, 255].
  const cv::Scalar ref = cv::quality::QualitySSIM::compute(a, b, cv::noArray());
  const double ref_mean = (ref[0] + ref[1] + ref[2]) / 3.0;
  const double ours = Ssim(a, b);
  CHECK(ours < 0.99);  // a real difference, not a trivial case
  CHECK(ours == Approx(ref_mean).margin(1e-4));
}

TEST_CASE("ComputeDepthErrors uses only pixels valid in both", "[unit]") {
  cv::Mat gt = (cv::Mat_<float>(2, 3) << 1.0f, 2.0f, 4.0f, 0.0f, 1.0f, NAN);
  cv::Mat pred = (cv::Mat_<float>(2, 3) << 1.5f, 2.0f, 0.0f, 3.0f, 0.5f, 2.0f);
  const DepthErrors e = ComputeDepthErrors(pred, gt);
  // Valid in both: (1.5 vs 1), (2 vs 2), (0.5 vs 1).
  REQUIRE(e.valid_pixels == 3);
  CHECK(e.gt_valid_pixels == 4);
  CHECK(e.total_pixels == 6);
  CHECK(e.valid_fraction == Approx(0.75));
  CHECK(e.abs_rel == Approx((0.5 + 0.0 + 0.5) / 3.0));
  CHECK(e.rmse_m == Approx(std::sqrt((0.25 + 0.0 + 0.25) / 3.0)));
  cv::Mat zeros = cv::Mat::zeros(2, 3, CV_32F);
  CHECK(std::isnan(ComputeDepthErrors(zeros, gt).abs_rel));
  CHECK_THROWS_AS(ComputeDepthErrors(cv::Mat::zeros(2, 3, CV_64F), gt), std::invalid_argument);
}

TEST_CASE("LatencyRecorder percentiles and throughput", "[unit]") {
  LatencyRecorder rec(3);
  CHECK(rec.Summary().count == 0);
  // Shuffled 1..100 ms: the percentiles come from sorted samples.
  for (int i = 0; i < 100; ++i) rec.Add(((i * 37) % 100 + 1) * 1e-3);
  const LatencySummary s = rec.Summary();
  CHECK(s.count == 100);
  CHECK(s.threads == 3);
  CHECK(s.p50_ms == Approx(50.0));
  CHECK(s.p99_ms == Approx(99.0));
  CHECK(s.min_ms == Approx(1.0));
  CHECK(s.max_ms == Approx(100.0));
  CHECK(s.mean_ms == Approx(50.5));
  CHECK(s.views_per_second == Approx(100.0 / 5.05));
  CHECK_THROWS_AS(rec.Add(-1.0), std::invalid_argument);
  LatencyRecorder timed;
  CHECK_THROWS_AS(timed.Stop(), std::logic_error);
  timed.Start();
  timed.Stop();
  CHECK(timed.Count() == 1);
}
