/// @file pose_dependence_test.cc
/// @brief model::PoseDependence: a constant model scores 0, one reproducing the ground truth 1,
/// half the contrast 0.5; bad input is refused; the warning threshold.
#include <cmath>
#include <random>
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/imgproc.hpp>

#include "model/pose_dependence.h"

using p2i::model::kPoseDependenceWarn;
using p2i::model::PoseDependence;
using p2i::model::PoseDependenceWarning;

namespace {

// Eight "views" of a scene: random 8-bit RGB images (seeded).
std::vector<cv::Mat> Views(int n = 8) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pick(20, 235);
  std::vector<cv::Mat> out;
  for (int i = 0; i < n; ++i) {
    cv::Mat m(16, 16, CV_8UC3);
    for (int y = 0; y < m.rows; ++y)
      for (int x = 0; x < m.cols; ++x)
        m.at<cv::Vec3b>(y, x) = cv::Vec3b(pick(rng), pick(rng), pick(rng));
    out.push_back(m);
  }
  return out;
}

}  // namespace

TEST_CASE("pose-dependence: constant output ~0, reproducing the ground truth 1, half contrast 0.5",
          "[unit]") {
  const auto gt = Views();
  cv::Mat mean = cv::Mat::zeros(16, 16, CV_64FC3);
  for (const auto& m : gt) cv::accumulate(m, mean);
  cv::Mat mean8;
  mean.convertTo(mean8, CV_8UC3, 1.0 / gt.size());

  PoseDependence constant, exact, half;
  for (const auto& m : gt) {
    constant.Add(mean8, m);  // one image for every pose (the mean image: a collapsed model)
    exact.Add(m, m);
    cv::Mat h;
    cv::addWeighted(m, 0.5, mean8, 0.5, 0.0, h);  // the right layout at half the contrast
    half.Add(h, m);
  }
  CHECK(constant.Count() == 8);
  CHECK(constant.Score() == Approx(0.0).margin(1e-12));
  CHECK(exact.Score() == Approx(1.0).epsilon(1e-12));
  CHECK(half.Score() == Approx(0.5).margin(0.02));  // 8-bit rounding
  CHECK(exact.TruthStd() > 30.0);                  // uniform 20..235: std ~62 grey levels
  CHECK(!PoseDependenceWarning(constant.Score()).empty());
  CHECK(PoseDependenceWarning(exact.Score()).empty());
}

TEST_CASE("pose-dependence: undefined with < 2 views or a static scene, bad input refused",
          "[unit]") {
  const auto gt = Views(2);
  PoseDependence one;
  one.Add(gt[0], gt[0]);
  CHECK(std::isnan(one.Score()));
  PoseDependence still;
  still.Add(gt[0], gt[1]);
  still.Add(gt[1], gt[1]);  // the ground truth never changes: no reference variation
  CHECK(std::isnan(still.Score()));
  CHECK(PoseDependenceWarning(std::nan("")).empty());

  PoseDependence p;
  cv::Mat small(8, 8, CV_8UC3, cv::Scalar::all(0));
  CHECK_THROWS_WITH(p.Add(small, gt[0]), Catch::Contains("differ in size"));
  CHECK_THROWS_WITH(p.Add(cv::Mat(), gt[0]), Catch::Contains("empty"));
  p.Add(gt[0], gt[0]);
  CHECK_THROWS_WITH(p.Add(small, small), Catch::Contains("size of the first"));
  CHECK(kPoseDependenceWarn == Approx(0.5));
  CHECK_THAT(PoseDependenceWarning(0.1), Catch::Contains("pose-dependence 0.10 < 0.50"));
}
