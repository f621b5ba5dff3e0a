/// @file baseline_warp_test.cc
/// @brief DIBR baseline: identity warp reproduces the frame, a fronto-parallel plane shifts by
/// fx * t / z pixels, holes are marked (fill off) or filled (fill on).
#include <cmath>

#include <catch2/catch.hpp>
#include <opencv2/imgproc.hpp>

#include <yaml-cpp/yaml.h>

#include "model/baseline_nearest.h"
#include "model/baseline_warp.h"
#include "model/coverage.h"
#include "model/metrics.h"

using namespace p2i::model;
using p2i::scene::Pose;

namespace {

constexpr int kW = 64;
constexpr int kH = 48;
constexpr double kF = 50.0;

p2i::scene::CameraInfo Cam() {
  return p2i::scene::CameraInfo::Pinhole(kW, kH, kF, kF, (kW - 1) / 2.0, (kH - 1) / 2.0);
}

cv::Mat Texture(uint64_t seed) {
  cv::Mat img(kH, kW, CV_8UC3);
  cv::RNG(seed).fill(img, cv::RNG::UNIFORM, 20, 256);  // >= 20: never confused with a hole
  return img;
}

p2i::scene::RgbdSample Frame(const Pose& pose, const cv::Mat& rgb, const cv::Mat& depth,
                             const std::string& id) {
  p2i::scene::RgbdSample s;
  s.pose = pose;
  s.rgb = rgb;
  s.depth = depth;
  s.id = id;
  return s;
}

Pose Translated(double x, double y, double z) {
  return Pose(Eigen::Vector3d(x, y, z), Eigen::Quaterniond::Identity());
}

}  // namespace

TEST_CASE("DepthWarp into a frame's own pose reproduces it", "[unit]") {
  // A slanted surface with a block of invalid depth, seen from a non-trivial pose.
  cv::Mat depth(kH, kW, CV_32FC1);
  for (int v = 0; v < kH; ++v)
    for (int u = 0; u < kW; ++u) depth.at<float>(v, u) = 1.5f + 0.01f * u + 0.005f * v;
  depth(cv::Rect(10, 12, 6, 5)).setTo(0.0f);
  depth.at<float>(30, 40) = NAN;
  const Pose pose(Eigen::Vector3d(0.3, -0.2, 1.1),
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 1.0, 0.1).normalized())));
  p2i::scene::RgbdDataset data;
  data.camera = Cam();
  data.frames.push_back(Frame(pose, Texture(1), depth, "a"));
  data.frames.push_back(Frame(Translated(3, 0, 0), Texture(2), depth, "far"));
  DepthWarpOptions opt;
  opt.k = 1;
  DepthWarp warp(data, opt);
  const p2i::scene::RgbdSample v = warp.Render(pose);
  REQUIRE(v.rgb.size() == cv::Size(kW, kH));
  // Zero or NaN (built by hand: cv::compare's treatment of NaN is not something to rely on).
  cv::Mat invalid = cv::Mat::zeros(kH, kW, CV_8UC1);
  for (int v = 0; v < kH; ++v)
    for (int u = 0; u < kW; ++u)
      if (!(depth.at<float>(v, u) > 0.0f)) invalid.at<uint8_t>(v, u) = 255;
  REQUIRE(cv::countNonZero(invalid) == 31);
  cv::Mat holes = v.depth == 0.0f;
  CHECK(cv::countNonZero(holes != invalid) == 0);  // holes exactly where depth is invalid
  CHECK(warp.LastHoleFraction() == Approx(31.0 / (kW * kH)));
  cv::Mat expected = data.frames[0].rgb.clone();
  expected.setTo(cv::Scalar::all(0), invalid);
  CHECK(Psnr(v.rgb, expected) == kPsnrCapDb);  // identical
  cv::Mat expected_depth = depth.clone();
  expected_depth.setTo(0.0f, invalid);
  CHECK(cv::norm(v.depth, expected_depth, cv::NORM_INF) < 1e-5);
}

TEST_CASE("DepthWarp shifts a fronto-parallel plane by fx * t / z pixels", "[unit]") {
  const double z = 2.0, t = 0.2;  // shift = 50 * 0.2 / 2 = 5 px
  const int shift = static_cast<int>(std::lround(kF * t / z));
  const cv::Mat rgb = Texture(7);
  p2i::scene::RgbdDataset data;
  data.camera = Cam();
  data.frames.push_back(Frame(Pose::Identity(), rgb, cv::Mat(kH, kW, CV_32FC1, cv::Scalar(z)), "p"));
  DepthWarp warp(data);
  // Camera moved to +x: the scene moves left in the image by `shift` pixels.
  const p2i::scene::RgbdSample v = warp.Render(Translated(t, 0.0, 0.0));
  const cv::Rect kept(0, 0, kW - shift, kH);
  CHECK(cv::norm(v.rgb(kept), rgb(cv::Rect(shift, 0, kW - shift, kH)), cv::NORM_INF) == 0.0);
  CHECK(cv::norm(v.depth(kept), cv::Mat(kH, kW - shift, CV_32FC1, cv::Scalar(z)), cv::NORM_INF) <
        1e-5);
  // The uncovered right strip is marked as holes.
  const cv::Rect strip(kW - shift, 0, shift, kH);
  CHECK(cv::countNonZero(v.depth(strip)) == 0);
  CHECK(cv::norm(v.rgb(strip), cv::NORM_INF) == 0.0);
  CHECK(warp.LastHoleFraction() == Approx(static_cast<double>(shift) / kW));
  // Moving the camera down (+y) shifts the image up by the same rule.
  const p2i::scene::RgbdSample vy = warp.Render(Translated(0.0, t, 0.0));
  CHECK(cv::norm(vy.rgb(cv::Rect(0, 0, kW, kH - shift)), rgb(cv::Rect(0, shift, kW, kH - shift)),
                 cv::NORM_INF) == 0.0);
}

TEST_CASE("DepthWarp hole fill closes the holes", "[unit]") {
  const cv::Mat rgb = Texture(9);
  p2i::scene::RgbdDataset data;
  data.camera = Cam();
  data.frames.push_back(
      Frame(Pose::Identity(), rgb, cv::Mat(kH, kW, CV_32FC1, cv::Scalar(2.0)), "p"));
  DepthWarpOptions opt;
  opt.fill_holes = true;
  DepthWarp warp(data, opt);
  const p2i::scene::RgbdSample v = warp.Render(Translated(0.2, 0.0, 0.0));
  CHECK(warp.LastHoleFraction() > 0.05);  // there were holes before filling
  CHECK(cv::countNonZero(v.depth == 0.0f) == 0);
  const cv::Rect strip(kW - 5, 0, 5, kH);
  // Filled depth continues the plane; filled colour is plausible (non-zero).
  CHECK(cv::norm(v.depth(strip), cv::Mat(kH, 5, CV_32FC1, cv::Scalar(2.0)), cv::NORM_INF) < 1e-4);
  cv::Mat grey;
  cv::cvtColor(v.rgb(strip), grey, cv::COLOR_RGB2GRAY);
  CHECK(cv::countNonZero(grey) == 5 * kH);
  // The pixels that were not holes are unchanged by the fill.
  CHECK(cv::norm(v.rgb(cv::Rect(0, 0, kW - 5, kH)), rgb(cv::Rect(5, 0, kW - 5, kH)),
                 cv::NORM_INF) == 0.0);
}

TEST_CASE("DepthWarp blends the k nearest frames and renders at a requested camera", "[unit]") {
  // Two views of the same textured plane; rendering between them with k = 2 fills what one frame
  // alone leaves empty.
  const double z = 2.0;
  cv::Mat world_tex(kH, kW + 20, CV_8UC3);
  cv::RNG(11).fill(world_tex, cv::RNG::UNIFORM, 20, 256);
  // Frame at x = 0 sees columns [0, kW); frame at x = 0.4 (10 px) sees columns [10, kW + 10).
  const cv::Mat left = world_tex(cv::Rect(0, 0, kW, kH)).clone();
  const cv::Mat right = world_tex(cv::Rect(10, 0, kW, kH)).clone();
  const cv::Mat plane(kH, kW, CV_32FC1, cv::Scalar(z));
  p2i::scene::RgbdDataset data;
  data.camera = Cam();
  data.frames.push_back(Frame(Pose::Identity(), left, plane, "l"));
  data.frames.push_back(Frame(Translated(0.4, 0, 0), right, plane, "r"));
  DepthWarpOptions one;
  one.k = 1;
  DepthWarp w1(data, one);
  w1.Render(Translated(0.2, 0, 0));
  const double holes_one = w1.LastHoleFraction();
  DepthWarp w2(data);  // k = 4 > 2 frames: both used
  const p2i::scene::RgbdSample v = w2.Render(Translated(0.2, 0, 0));
  CHECK(holes_one > 0.0);
  CHECK(w2.LastHoleFraction() == 0.0);
  // Consistent sources blend to the same texture: columns [5, kW + 5) of the world.
  CHECK(Psnr(v.rgb, world_tex(cv::Rect(5, 0, kW, kH))) == kPsnrCapDb);
  // Requested output camera: half resolution.
  const auto half = p2i::scene::CameraInfo::Pinhole(kW / 2, kH / 2, kF / 2, kF / 2,
                                                    (kW / 2 - 1) / 2.0, (kH / 2 - 1) / 2.0);
  DepthWarp wh(data, DepthWarpOptions{}, half);
  const p2i::scene::RgbdSample vh = wh.Render(Pose::Identity());
  CHECK(vh.rgb.size() == cv::Size(kW / 2, kH / 2));
  CHECK(wh.Camera().image_width == kW / 2);
  CHECK(cv::countNonZero(vh.depth) > kW * kH / 8);
}

TEST_CASE("DepthWarpOptions and CoverageOptions from YAML", "[unit]") {
  const YAML::Node node = YAML::Load("{k: 2, z_tolerance: 0.1, fill_holes: true}");
  const DepthWarpOptions o = DepthWarpOptions::FromYaml(node, "bench.yaml");
  CHECK(o.k == 2);
  CHECK(o.z_tolerance == Approx(0.1));
  CHECK(o.fill_holes);
  CHECK(o.metres_per_degree == Approx(DepthWarpOptions{}.metres_per_degree));
  try {
    DepthWarpOptions::FromYaml(YAML::Load("{k: 2, fil_holes: true}"), "bench.yaml");
    FAIL("unknown key accepted");
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    CHECK(what.find("bench.yaml") != std::string::npos);
    CHECK(what.find("fil_holes") != std::string::npos);
  }
  CHECK_THROWS_AS(DepthWarpOptions::FromYaml(YAML::Load("{k: 0}"), "b.yaml"), std::runtime_error);
  CHECK_THROWS_AS(DepthWarpOptions::FromYaml(YAML::Load("{k: 1.5}"), "b.yaml"), std::runtime_error);
  CHECK(NearestKeyframeOptions::FromYaml(YAML::Load("{metres_per_degree: 0.02}"), "b.yaml")
            .metres_per_degree == Approx(0.02));
  CHECK(CoverageOptions::FromYaml(YAML::Load("{falloff: 3}"), "b.yaml").falloff == Approx(3.0));
  CHECK_THROWS_AS(CoverageOptions::FromYaml(YAML::Load("{falloff: -1}"), "b.yaml"),
                  std::runtime_error);
}
