/// @file lpips_test.cc
/// @brief LPIPS-Squeeze against the upstream reference values of ../shared/models/lpips/testdata
/// (skips with a message when the weights are absent), plus the missing-weights path.
#include <cstdlib>
#include <filesystem>
#include <string>

#include <catch2/catch.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "model/lpips.h"
#include "tests/skip.h"
#include "tests/test_paths.h"

using namespace p2i::model;

namespace {

std::string LpipsDir() { return p2i::testing::SharedDir() + "/models/lpips"; }

cv::Mat LoadRgb(const std::string& name) {
  cv::Mat bgr = cv::imread(LpipsDir() + "/testdata/" + name, cv::IMREAD_COLOR);
  REQUIRE_FALSE(bgr.empty());
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return rgb;
}

}  // namespace

TEST_CASE("LpipsSqueeze reproduces the upstream reference values", "[unit]") {
  const std::string weights = LpipsDir() + "/lpips_squeeze_v0.1.pth";
  std::string why;
  auto metric = LpipsSqueeze::TryLoad(weights, &why);
  if (!metric) P2I_SKIP(why);
  const cv::Mat ref = LoadRgb("ex_ref.png");
  const cv::Mat p0 = LoadRgb("ex_p0.png");
  const cv::Mat p1 = LoadRgb("ex_p1.png");
  CHECK(metric->Distance(ref, p0) == Approx(0.711047).margin(1e-4));
  CHECK(metric->Distance(ref, p1) == Approx(0.147902).margin(1e-4));
  CHECK(metric->Distance(ref, ref) == Approx(0.0).margin(1e-9));
  // Float input in [0, 1] gives the same numbers as 8-bit input.
  cv::Mat ref_f, p1_f;
  ref.convertTo(ref_f, CV_32F, 1.0 / 255.0);
  p1.convertTo(p1_f, CV_32F, 1.0 / 255.0);
  CHECK(metric->Distance(ref_f, p1_f) == Approx(0.147902).margin(1e-4));
  // The batched form gives the same values as single calls, including mixed sizes.
  cv::Mat small_a, small_b;
  cv::resize(ref, small_a, cv::Size(32, 32), 0, 0, cv::INTER_AREA);
  cv::resize(p0, small_b, cv::Size(32, 32), 0, 0, cv::INTER_AREA);
  const auto batch = metric->DistanceBatch({ref, small_a, ref}, {p0, small_b, p1});
  REQUIRE(batch.size() == 3);
  CHECK(batch[0] == Approx(0.711047).margin(1e-4));
  CHECK(batch[1] == Approx(metric->Distance(small_a, small_b)).margin(1e-6));
  CHECK(batch[2] == Approx(0.147902).margin(1e-4));
  CHECK(LpipsSqueezeOrMissing(metric.get(), ref, p1).has_value());
  CHECK_THROWS_AS(metric->Distance(ref, small_a), std::invalid_argument);
}

TEST_CASE("LpipsSqueeze reports missing weights", "[unit]") {
  std::string why;
  auto metric = LpipsSqueeze::TryLoad("/nonexistent/lpips.pth", &why);
  CHECK(metric == nullptr);
  CHECK(why.find("LPIPS-Squeeze unavailable: set P2I_LPIPS_WEIGHTS or --lpips-weights") !=
        std::string::npos);
  CHECK(why.find("/nonexistent/lpips.pth") != std::string::npos);
  cv::Mat img(16, 16, CV_8UC3, cv::Scalar::all(0));
  CHECK_FALSE(LpipsSqueezeOrMissing(metric.get(), img, img).has_value());
  CHECK(LpipsSqueeze::ResolveWeightsPath("x.pth") == "x.pth");
  // A file that exists but is not a state dict is an error, not "missing".
  const std::string bogus = p2i::testing::BinaryDir() + "/lpips_bogus_test.pth";
  { std::FILE* f = std::fopen(bogus.c_str(), "wb"); REQUIRE(f); std::fputs("junk", f); std::fclose(f); }
  CHECK_THROWS_AS(LpipsSqueeze::TryLoad(bogus), std::runtime_error);
  std::remove(bogus.c_str());
}
