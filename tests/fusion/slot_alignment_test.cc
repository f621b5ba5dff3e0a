/// @file slot_alignment_test.cc
/// @brief Floating textures (fusion/slot_alignment.h): two slots of one texture, shifted against
/// each other, line up and blend sharper; the shift limit holds; off changes nothing; the blend
/// options read and check the keys; FusionScene aligns only when asked and still releases the
/// slot planes a view did not request.
#include <memory>

#include <catch2/catch.hpp>

#include <opencv2/imgproc.hpp>
#include <yaml-cpp/yaml.h>

#include "fusion/fusion_scene.h"
#include "fusion/slot_alignment.h"
#include "model/metrics.h"
#include "tests/fusion/fusion_test_util.h"

namespace p2i::fusion {
namespace {

constexpr int kSize = 64;

/// A smooth random texture (CV_32FC3 in [0.1, 0.9]) seen through a window shifted by `dx`.
cv::Mat Texture(float dx) {
  cv::RNG rng(7);
  cv::Mat coarse(20, 20, CV_32FC3);
  rng.fill(coarse, cv::RNG::UNIFORM, 0.1, 0.9);
  cv::Mat fine;
  cv::resize(coarse, fine, cv::Size(80, 80), 0, 0, cv::INTER_CUBIC);
  cv::Mat out;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, 8 + dx, 0, 1, 8);
  cv::warpAffine(fine, out, shift, cv::Size(kSize, kSize), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP);
  return out;
}

/// Two slots, the second the first shifted by `dx` pixels, weighted 0.5 each everywhere.
ViewCandidates TwoShiftedSlots(float dx) {
  ViewCandidates c;
  c.colours = {Texture(0.0f), Texture(dx)};
  c.weights = {cv::Mat(kSize, kSize, CV_32FC1, cv::Scalar(0.5)), cv::Mat(kSize, kSize, CV_32FC1, cv::Scalar(0.5))};
  c.blended = 0.5 * c.colours[0] + 0.5 * c.colours[1];
  c.depth = cv::Mat(kSize, kSize, CV_32FC1, cv::Scalar(1.0f));
  return c;
}

const cv::Rect kInner(8, 8, kSize - 16, kSize - 16);  // away from the borders the shift exposes

double MeanAbsDiff(const cv::Mat& a, const cv::Mat& b) {
  const cv::Scalar m = cv::mean(cv::abs(a(kInner) - b(kInner)));
  return (m[0] + m[1] + m[2]) / 3.0;
}

double GradientEnergy(const cv::Mat& rgb) {
  cv::Mat gx, gy;
  cv::Sobel(rgb(kInner), gx, CV_32F, 1, 0);
  cv::Sobel(rgb(kInner), gy, CV_32F, 0, 1);
  const cv::Scalar s = cv::sum(gx.mul(gx) + gy.mul(gy));
  return s[0] + s[1] + s[2];
}

TEST_CASE("Slot alignment: slots shifted against each other line up, the blend is sharper", "[unit]") {
  ViewCandidates c = TwoShiftedSlots(2.0f);
  const double before = MeanAbsDiff(c.colours[0], c.colours[1]);
  const double sharp_before = GradientEnergy(c.blended);
  const cv::Scalar mean_before = cv::mean(c.blended(kInner));
  const cv::Mat w0 = c.weights[0].clone();
  SlotAlignmentOptions o;
  o.iterations = 2;
  AlignSlots(o, &c);
  const double after = MeanAbsDiff(c.colours[0], c.colours[1]);
  INFO("slot difference " << before << " -> " << after);
  CHECK(after < 0.4 * before);
  CHECK(GradientEnergy(c.blended) > 1.2 * sharp_before);
  const cv::Scalar mean_after = cv::mean(c.blended(kInner));
  for (int ch = 0; ch < 3; ++ch) CHECK(mean_after[ch] == Approx(mean_before[ch]).margin(0.01));
  CHECK(cv::norm(w0, c.weights[0], cv::NORM_INF) == 0.0);  // the weights stay
  // The blend is the weighted sum of the aligned slots.
  CHECK(cv::norm(c.blended, 0.5 * c.colours[0] + 0.5 * c.colours[1], cv::NORM_INF) < 1e-5);
}

TEST_CASE("Slot alignment: off changes nothing, and no slot moves further than the limit", "[unit]") {
  ViewCandidates off = TwoShiftedSlots(2.0f);
  const cv::Mat blend = off.blended.clone();
  AlignSlots(SlotAlignmentOptions{}, &off);  // iterations 0
  CHECK(cv::norm(blend, off.blended, cv::NORM_INF) == 0.0);

  ViewCandidates limited = TwoShiftedSlots(2.0f);
  const double before = MeanAbsDiff(limited.colours[0], limited.colours[1]);
  SlotAlignmentOptions o;
  o.iterations = 1;
  o.max_shift_px = 0.2;  // each slot may move 0.2 px towards the blend: 0.4 of the 2 px apart
  AlignSlots(o, &limited);
  const double after = MeanAbsDiff(limited.colours[0], limited.colours[1]);
  INFO("slot difference " << before << " -> " << after);
  CHECK(after > 0.6 * before);
  CHECK(after < before);
}

TEST_CASE("Slot alignment: the blend options read and check align_*", "[unit]") {
  const BlendOptions o =
      BlendOptions::FromYaml(YAML::Load("{align_iterations: 2, align_max_shift_px: 1.5}"), "cfg.yaml");
  CHECK(o.align.iterations == 2);
  CHECK(o.align.max_shift_px == 1.5);
  CHECK_FALSE(BlendOptions::FromYaml(YAML::Load("{align_iterations: 2}"), "cfg.yaml").align.automatic);
  CHECK(BlendOptions::FromYaml(YAML::Load("{align_iterations: 0}"), "cfg.yaml").align.iterations == 0);
  // auto by default: one round where the leave-one-out shows it pays (align_choice.h)
  CHECK(BlendOptions{}.align.automatic);
  CHECK(BlendOptions{}.align.iterations == 1);
  CHECK(BlendOptions::FromYaml(YAML::Load("{}"), "cfg.yaml").align.automatic);
  CHECK_THROWS_WITH(BlendOptions::FromYaml(YAML::Load("{align_iterations: 9}"), "cfg.yaml"),
                    Catch::Contains("cfg.yaml") && Catch::Contains("align_iterations"));
  CHECK_THROWS_WITH(BlendOptions::FromYaml(YAML::Load("{align_max_shift_px: 0}"), "cfg.yaml"),
                    Catch::Contains("align_max_shift_px"));
  CHECK(BlendOptions::FromYaml(YAML::Load("{align_flow_preset: fast}"), "cfg.yaml").align.flow_preset == "fast");
  CHECK_THROWS_WITH(BlendOptions::FromYaml(YAML::Load("{align_flow_preset: slow}"), "cfg.yaml"),
                    Catch::Contains("align_flow_preset") && Catch::Contains("ultrafast, fast or medium"));
}

TEST_CASE("Slot alignment: FusionScene aligns when asked and keeps exact views exact", "[unit]") {
  const testing::PlaneScene scene;
  const auto cam = testing::Cam(64, 48, 60);
  FusionSceneOptions plain;
  plain.blend.align = SlotAlignmentOptions{};  // off
  FusionSceneOptions aligned;
  aligned.blend.align = SlotAlignmentOptions{};
  aligned.blend.align.iterations = 2;  // in every view
  FusionScene a(cam, plain), b(cam, aligned);
  for (double x : {-0.1, 0.0, 0.1}) {
    a.AddFrame(scene.Render(testing::At(x, 0, 0), cam));
    b.AddFrame(scene.Render(testing::At(x, 0, 0), cam));
  }
  const scene::RgbdSample gt = scene.Render(testing::At(0.04, 0.01, 0), cam);
  CandidateRequest lean;
  lean.slot_planes = false;
  const ViewCandidates va = a.RenderCandidates(gt.pose, cam, lean);
  const ViewCandidates vb = b.RenderCandidates(gt.pose, cam, lean);
  for (int j = 0; j < vb.k(); ++j) CHECK(vb.colours[j].empty());  // released: not requested
  CHECK(cv::norm(va.blended, vb.blended, cv::NORM_INF) > 0.0);      // it did run
  cv::Mat ra, rb;
  va.blended.convertTo(ra, CV_8UC3, 255.0);
  vb.blended.convertTo(rb, CV_8UC3, 255.0);
  gt.rgb.copyTo(ra, va.observed == 0);
  gt.rgb.copyTo(rb, vb.observed == 0);
  // Exact poses and geometry: nothing to align, so the aligned blend stays as good.
  CHECK(model::Psnr(rb, gt.rgb) > model::Psnr(ra, gt.rgb) - 0.5);
}

TEST_CASE("Slot alignment: a view aligns the same after a view of another size", "[unit]") {
  // The flow objects are kept between views; one that had seen another size used to give a
  // different flow (OpenCV's DIS keeps state from the first size it sees).
  testing::PlaneScene scene;
  scene.detail = 40.0;
  const auto build = [&](const scene::CameraInfo& cam) {
    FusionSceneOptions o;
    o.blend.visibility_abs_m = 0.6;  // the off geometry below stays visible, so slots misregister
    o.blend.align = SlotAlignmentOptions{};
    o.blend.align.iterations = 1;  // in every view
    auto fs = std::make_unique<FusionScene>(cam, o);
    testing::AddOverScaledGeometry(scene, cam, {-0.16, -0.08, 0.0, 0.08, 0.16}, 1.25, fs.get());
    return fs;
  };
  const auto big = testing::Cam(128, 96, 120);
  const auto small = testing::Cam(64, 48, 60);
  auto a = build(big);
  auto b = build(small);
  CandidateRequest lean;
  lean.slot_planes = false;
  const scene::Pose pose = testing::At(0.04, 0, 0);
  const ViewCandidates first = a->RenderCandidates(pose, big, lean);
  const ViewCandidates other = b->RenderCandidates(pose, small, lean);
  const ViewCandidates again = a->RenderCandidates(pose, big, lean);
  lean.align = false;
  const ViewCandidates unaligned = a->RenderCandidates(pose, big, lean);
  CHECK(cv::norm(first.blended, unaligned.blended, cv::NORM_INF) > 0.01);  // the flow did move slots
  CHECK(cv::norm(first.blended, again.blended, cv::NORM_INF) == 0.0);
  CHECK(other.blended.cols == 64);
}

}  // namespace
}  // namespace p2i::fusion
