/// @file fusion_scene_test.cc
/// @brief FusionScene: keyframe blending with visibility, view-dependent weights, coverage, and
/// the refinement tensor layout.
#include <algorithm>
#include <numeric>
#include <vector>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "fusion/fusion_scene.h"
#include "model/metrics.h"
#include "tests/fusion/fusion_test_util.h"

namespace p2i::fusion {
namespace {

using testing::At;
using testing::Cam;
using testing::PlaneScene;

cv::Mat To8U(const cv::Mat& f) {
  cv::Mat o;
  f.convertTo(o, CV_8UC3, 255.0);
  return o;
}

TEST_CASE("FusionScene: a training view is reproduced by its own keyframe", "[unit]") {
  const PlaneScene scene;
  const auto cam = Cam(80, 60, 70);
  FusionScene fs(cam);
  for (double x : {-0.15, -0.05, 0.05, 0.15}) CHECK(fs.AddFrame(scene.Render(At(x, 0, 0), cam)));
  const scene::RgbdSample gt = scene.Render(At(0.05, 0, 0), cam);
  const ViewCandidates c = fs.RenderCandidates(gt.pose, cam);
  REQUIRE(c.k() == 4);
  CHECK(c.keyframe_indices[0] == 2);  // nearest first
  CHECK(c.coverage.observed_fraction > 0.95);
  CHECK(c.coverage.mean_angle_deg < 0.5);
  // The keyframe at the pose dominates every pixel it sees.
  CHECK(cv::mean(c.weights[0])[0] > 0.9);
  cv::Mat blended = To8U(c.blended);
  gt.rgb.copyTo(blended, c.observed == 0);  // score the observed pixels only
  CHECK(model::Psnr(blended, gt.rgb) > 35.0);
}

TEST_CASE("FusionScene: slot weights sum to one where blended, zero elsewhere", "[unit]") {
  const PlaneScene scene;
  const auto cam = Cam(64, 48, 60);
  FusionScene fs(cam);
  fs.AddFrame(scene.Render(At(-0.1, 0, 0), cam));
  fs.AddFrame(scene.Render(At(0.1, 0, 0), cam));
  const ViewCandidates c = fs.RenderCandidates(At(0.3, 0, 0), Cam(40, 30, 38));
  REQUIRE(c.k() == 4);
  CHECK(c.keyframe_indices[2] == -1);  // only two keyframes exist
  int blended = 0;
  for (int v = 0; v < 30; ++v)
    for (int u = 0; u < 40; ++u) {
      float s = 0;
      for (int j = 0; j < 4; ++j) s += c.weights[j].at<float>(v, u);
      if (c.confidence.at<float>(v, u) > 0) {
        ++blended;
        CHECK(s == Approx(1.0f).margin(1e-4));
      } else {
        CHECK(s == 0.0f);
      }
    }
  CHECK(blended > 0);
  // The view at x = 0.3 sees the plane beyond what the keyframes covered on its right side.
  CHECK(c.coverage.blended_fraction < 1.0);
  CHECK(c.coverage.mean_angle_deg > 1.0);
}

TEST_CASE("FusionScene: a keyframe whose own depth disagrees is masked by visibility", "[unit]") {
  const PlaneScene scene;
  const auto cam = Cam(64, 48, 60);
  FusionScene fs(cam);
  fs.AddFrame(scene.Render(At(0.0, 0, 0), cam));
  // The nearest keyframe to the query has a depth map 0.5 m short of the true plane and a
  // magenta image; its geometry is not fused (integrate = false), so the TSDF holds the truth.
  scene::RgbdSample liar = scene.Render(At(0.02, 0, 0), cam);
  liar.rgb.setTo(cv::Scalar(255, 0, 255));
  liar.depth -= 0.5f;
  fs.AddFrame(liar, /*integrate=*/false);
  CHECK(fs.Stats().frames == 1);
  const scene::Pose query = At(0.02, 0, 0);
  const ViewCandidates c = fs.RenderCandidates(query, cam);
  REQUIRE(c.keyframe_indices[0] == 1);  // the liar is the nearest keyframe
  int checked = 0;
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) {
      if (c.depth.at<float>(v, u) <= 0.0f) continue;
      ++checked;
      CHECK(c.weights[0].at<float>(v, u) == 0.0f);
    }
  CHECK(checked > 0.9 * 64 * 48);
  const cv::Mat gt = scene.Render(query, cam).rgb;
  cv::Mat blended = To8U(c.blended);
  gt.copyTo(blended, c.observed == 0);
  CHECK(model::Psnr(blended, gt) > 30.0);  // no magenta
}

TEST_CASE("FusionScene: a wall point hidden from a keyframe by a box takes no colour from it", "[unit]") {
  PlaneScene scene;
  scene.patch_z = 1.2;
  scene.patch_half = 0.15;
  const auto cam = Cam(64, 48, 50);
  FusionScene fs(cam);
  // Keyframe 0 straight in front of the box; keyframe 1 to the side sees the wall behind it.
  fs.AddFrame(scene.Render(At(0.0, 0, 0), cam));
  fs.AddFrame(scene.Render(At(0.5, 0, 0), cam));
  const scene::Pose query = At(0.45, 0, 0);
  const ViewCandidates c = fs.RenderCandidates(query, cam);
  REQUIRE(c.keyframe_indices[0] == 1);
  REQUIRE(c.keyframe_indices[1] == 0);
  // Pixels of the query showing the wall (z ~ 2) whose ray from keyframe 0 passes through the box.
  const Eigen::Vector3d c0(0, 0, 0);
  int hidden = 0;
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) {
      const float z = c.depth.at<float>(v, u);
      if (std::abs(z - 2.0f) > 0.03f) continue;
      const Eigen::Vector3d x(0.45 + (u - cam.cx()) / cam.fx() * z, (v - cam.cy()) / cam.fy() * z, z);
      const Eigen::Vector3d at_box = c0 + (x - c0) * (1.2 / x.z());
      if (std::abs(at_box.x()) > 0.13 || std::abs(at_box.y()) > 0.13) continue;
      ++hidden;
      CHECK(c.weights[1].at<float>(v, u) == 0.0f);
    }
  CHECK(hidden > 20);
}

TEST_CASE("FusionScene: exclude_keyframe leaves a frame out of the colour sources", "[unit]") {
  const PlaneScene scene;
  const auto cam = Cam(48, 36, 45);
  FusionScene fs(cam);
  for (double x : {-0.1, 0.0, 0.1}) fs.AddFrame(scene.Render(At(x, 0, 0), cam));
  CandidateRequest req;
  req.exclude_keyframe = 1;
  const ViewCandidates c = fs.RenderCandidates(At(0, 0, 0), cam, req);
  for (int idx : c.keyframe_indices) CHECK(idx != 1);
  CHECK(c.keyframe_indices[0] >= 0);
  CHECK(c.coverage.mean_angle_deg > 0.5);  // its own view is no longer there
}

TEST_CASE("FusionScene: without slot planes the per-slot maps are empty, the blend the same", "[unit]") {
  const PlaneScene scene;
  const auto cam = Cam(48, 36, 45);
  FusionScene fs(cam);
  for (double x : {-0.1, 0.0, 0.1}) fs.AddFrame(scene.Render(At(x, 0, 0), cam));
  const ViewCandidates full = fs.RenderCandidates(At(0.04, 0.01, 0), cam);
  CandidateRequest req;
  req.slot_planes = false;
  const ViewCandidates lean = fs.RenderCandidates(At(0.04, 0.01, 0), cam, req);
  REQUIRE(full.k() == 4);
  REQUIRE(lean.k() == 4);
  for (int j = 0; j < 4; ++j) {
    CHECK(lean.colours[j].empty());
    CHECK(lean.weights[j].empty());
    CHECK_FALSE(full.weights[j].empty());
  }
  CHECK(cv::countNonZero(full.weights[0]) > 0);  // the full render did write the maps
  CHECK(cv::norm(full.blended, lean.blended, cv::NORM_INF) == 0.0);
  CHECK(cv::norm(full.confidence, lean.confidence, cv::NORM_INF) == 0.0);
  CHECK(cv::norm(full.depth, lean.depth, cv::NORM_INF) == 0.0);
  CHECK(lean.coverage.observed_fraction == full.coverage.observed_fraction);
  CHECK(lean.coverage.score == full.coverage.score);
  // A refinement cannot be fed from such a view: the packer says so.
  std::vector<float> packed;
  CHECK_THROWS_AS(PackRefinementInput(lean, &packed), std::invalid_argument);
}

TEST_CASE("FusionScene: keyframe_min_distance thins the keyframes, not the TSDF", "[unit]") {
  const PlaneScene scene;
  const auto cam = Cam(32, 24, 30);
  FusionSceneOptions o;
  o.blend.keyframe_min_distance = 0.05;
  FusionScene fs(cam, o);
  CHECK(fs.AddFrame(scene.Render(At(0, 0, 0), cam)));
  CHECK_FALSE(fs.AddFrame(scene.Render(At(0.01, 0, 0), cam)));
  CHECK(fs.AddFrame(scene.Render(At(0.1, 0, 0), cam)));
  CHECK(fs.keyframes().size() == 2);
  CHECK(fs.Stats().frames == 3);
}

// The median over observed pixels of a view's depth divided by the ground truth's.
double MedianDepthRatio(const cv::Mat& depth, const cv::Mat& truth) {
  std::vector<double> r;
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u)
      if (depth.at<float>(v, u) > 0.0f && truth.at<float>(v, u) > 0.0f)
        r.push_back(depth.at<float>(v, u) / truth.at<float>(v, u));
  if (r.empty()) return 0.0;
  std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
  return r[r.size() / 2];
}

TEST_CASE("FusionScene: blend depth keyframes reads the keyframes' own depth, raycast the TSDF's", "[unit]") {
  const PlaneScene scene;
  const auto cam = Cam(48, 36, 45);
  // The TSDF holds the true surface; the keyframes (colour sources only) measured it 1.5 % deeper,
  // inside the visibility test's 3 %, as a depth sensor's bias would.
  FusionSceneOptions raycast, keyframes;
  keyframes.blend.depth = "keyframes";
  FusionScene a(cam, raycast), b(cam, keyframes);
  for (double x : {-0.1, 0.0, 0.1}) {
    const scene::RgbdSample truth = scene.Render(At(x, 0, 0), cam);
    scene::RgbdSample biased = truth;
    const cv::Mat deeper = truth.depth * 1.015;  // a new buffer: biased shares truth's
    biased.depth = deeper;
    for (FusionScene* fs : {&a, &b}) {
      fs->Integrate(truth);
      fs->AddFrame(biased, /*integrate=*/false);
    }
  }
  const scene::RgbdSample gt = scene.Render(At(0.03, 0.01, 0), cam);
  const ViewCandidates va = a.RenderCandidates(gt.pose, cam);
  const ViewCandidates vb = b.RenderCandidates(gt.pose, cam);
  CHECK(MedianDepthRatio(va.depth, gt.depth) == Approx(1.0).margin(0.004));
  CHECK(MedianDepthRatio(vb.depth, gt.depth) == Approx(1.015).margin(0.004));
  CHECK(cv::norm(va.blended, vb.blended, cv::NORM_INF) == 0.0);  // colour is the same either way
  CHECK_THROWS_WITH(BlendOptions::FromYaml(YAML::Load("{depth: sensor}"), "cfg.yaml"),
                    Catch::Contains("cfg.yaml") && Catch::Contains("raycast, keyframes or auto"));
}

TEST_CASE("FusionScene: keyframe_denoise smooths the colour the blend reads, not the keyframes kept", "[unit]") {
  const PlaneScene scene;
  const auto cam = Cam(64, 48, 55);
  FusionSceneOptions smoothed;
  smoothed.blend.keyframe_denoise = 24.0;
  FusionScene plain(cam), denoised(cam, smoothed);
  cv::RNG rng(7);
  std::vector<cv::Mat> noisy_rgb;
  for (double x : {-0.1, 0.0, 0.1}) {
    scene::RgbdSample f = scene.Render(At(x, 0, 0), cam);
    cv::Mat noise(f.rgb.size(), CV_16SC3), rgb16;
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 4.0);  // a camera's RGB noise, 4 grey levels
    f.rgb.convertTo(rgb16, CV_16SC3);
    cv::Mat noisy = rgb16 + noise;
    noisy.convertTo(f.rgb, CV_8UC3);  // saturates
    noisy_rgb.push_back(f.rgb.clone());
    plain.AddFrame(f);
    denoised.AddFrame(f);
  }
  const scene::RgbdSample gt = scene.Render(At(0.0, 0, 0), cam);  // clean, at a keyframe's pose
  const ViewCandidates vp = plain.RenderCandidates(gt.pose, cam);
  const ViewCandidates vd = denoised.RenderCandidates(gt.pose, cam);
  cv::Mat bp = To8U(vp.blended), bd = To8U(vd.blended);
  gt.rgb.copyTo(bp, vp.observed == 0);  // score the observed pixels only
  gt.rgb.copyTo(bd, vp.observed == 0);
  const double psnr_plain = model::Psnr(bp, gt.rgb);
  const double psnr_denoised = model::Psnr(bd, gt.rgb);
  INFO("PSNR against the clean frame: plain " << psnr_plain << ", denoised " << psnr_denoised);
  CHECK(psnr_denoised > psnr_plain + 2.0);
  // The keyframes stay as captured (the refinement trains on them).
  REQUIRE(denoised.keyframes().size() == noisy_rgb.size());
  for (size_t i = 0; i < noisy_rgb.size(); ++i)
    CHECK(cv::norm(denoised.keyframes()[i].rgb, noisy_rgb[i], cv::NORM_INF) == 0.0);
  CHECK_THROWS_WITH(BlendOptions::FromYaml(YAML::Load("{keyframe_denoise: -1}"), "cfg.yaml"),
                    Catch::Contains("cfg.yaml") && Catch::Contains("keyframe_denoise"));
}

TEST_CASE("PackRefinementInput: channel layout of view_candidates.h", "[unit]") {
  const PlaneScene scene;
  const auto cam = Cam(20, 16, 18);
  FusionScene fs(cam);
  fs.AddFrame(scene.Render(At(0, 0, 0), cam));
  fs.AddFrame(scene.Render(At(0.05, 0, 0), cam));
  const ViewCandidates c = fs.RenderCandidates(At(0.01, 0, 0), cam);
  std::vector<float> t;
  PackRefinementInput(c, &t, 0.5f);
  const int k = c.k(), plane = 20 * 16;
  REQUIRE(t.size() == static_cast<size_t>(RefinementChannels(k) * plane));
  const int u = 10, v = 8, i = v * 20 + u;
  CHECK(t[1 * plane + i] == c.colours[0].at<cv::Vec3f>(v, u)[1]);       // slot 0, G
  CHECK(t[(3 * 1 + 2) * plane + i] == c.colours[1].at<cv::Vec3f>(v, u)[2]);  // slot 1, B
  CHECK(t[(3 * k + 1) * plane + i] == c.weights[1].at<float>(v, u));
  CHECK(t[(4 * k) * plane + i] == c.blended.at<cv::Vec3f>(v, u)[0]);
  CHECK(t[(4 * k + 3) * plane + i] == c.confidence.at<float>(v, u));
  CHECK(t[(4 * k + 4) * plane + i] == Approx(0.5f * c.depth.at<float>(v, u)));
  CHECK(t[(4 * k + 7) * plane + i] == c.normals.at<cv::Vec3f>(v, u)[2]);
  CHECK(t[(4 * k + 8) * plane + i] == 1.0f);
  CHECK(t[(4 * k + 11) * plane + i] == c.tsdf_colour.at<cv::Vec3f>(v, u)[2]);
}

}  // namespace
}  // namespace p2i::fusion
