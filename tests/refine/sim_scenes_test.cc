/// @file sim_scenes_test.cc
/// @brief The randomised sim scenes of the cross-scene refinement: deterministic, and their
/// materials and lights differ from the base scene and from each other.
#include <catch2/catch.hpp>

#include "refine/sim_scenes.h"

using namespace p2i;

namespace {

// Small, fast scenes: two of `frames` frames each at 32x24.
refine::SimScenesOptions SmallScenes(int frames) {
  refine::SimScenesOptions o;
  o.scenes = 2;
  o.frames = frames;
  o.width = 32;
  o.height = 24;
  return o;
}

}  // namespace

TEST_CASE("Randomised sim scenes are deterministic and differ from the base", "[unit]") {
  const scene::SimScene base = scene::SimScene::BuiltIn("small_office");
  const scene::SimScene a = refine::MakeSimVariant("small_office", 1, 7);
  const scene::SimScene b = refine::MakeSimVariant("small_office", 1, 7);
  const scene::SimScene c = refine::MakeSimVariant("small_office", 2, 7);
  CHECK(a.description().materials[0].color == b.description().materials[0].color);
  CHECK(a.description().materials[0].color != base.description().materials[0].color);
  CHECK(a.description().materials[0].color != c.description().materials[0].color);
  CHECK(a.description().lights[0].intensity != base.description().lights[0].intensity);
  CHECK(a.sensor_options().AnyEnabled());  // index 1: sensor model on

  refine::SimScenesOptions o = SmallScenes(3);
  const auto scenes = refine::MakeSimScenes(o);
  REQUIRE(scenes.size() == 2);
  CHECK(scenes[0].name == "small_office_v0");
  CHECK(scenes[1].name == "large_office_v1");
  REQUIRE(scenes[0].frames.frames.size() == 3);
  CHECK(scenes[0].frames.frames[0].rgb.cols == 32);
  CHECK(cv::countNonZero(scenes[0].frames.frames[0].depth > 0) > 32 * 24 / 2);
  o.frames = 1;
  CHECK_THROWS_AS(refine::MakeSimScenes(o), std::invalid_argument);
}

TEST_CASE("Randomised sim scenes: recorded-pose error and the realistic sensor", "[unit]") {
  refine::SimScenesOptions o = SmallScenes(4);
  const auto exact = refine::MakeSimScenes(o);
  o.pose_noise_m = 0.02;
  o.pose_noise_deg = 1.0;
  const auto noisy = refine::MakeSimScenes(o);
  REQUIRE(noisy.size() == exact.size());
  double max_t = 0.0, max_r = 0.0;
  for (size_t s = 0; s < exact.size(); ++s) {
    REQUIRE(noisy[s].frames.frames.size() == exact[s].frames.frames.size());
    for (size_t f = 0; f < exact[s].frames.frames.size(); ++f) {
      const auto& a = exact[s].frames.frames[f];
      const auto& b = noisy[s].frames.frames[f];
      // The same image (rendered at the true pose), a different recorded pose.
      CHECK(cv::norm(a.rgb, b.rgb, cv::NORM_INF) == 0.0);
      const double t = scene::Pose::TranslationDistance(a.pose, b.pose);
      const double r = scene::Pose::RotationDistanceDeg(a.pose, b.pose);
      CHECK(t < 0.02 * 6.0);  // 6 sigma of a 3-d Gaussian's norm at most
      CHECK(r < 1.0 * 6.0);
      max_t = std::max(max_t, t);
      max_r = std::max(max_r, r);
    }
  }
  CHECK(max_t > 1e-4);
  CHECK(max_r > 1e-3);

  std::mt19937_64 rng(3);
  const scene::Pose p = exact[0].frames.frames[0].pose;
  CHECK(refine::PerturbPose(p, 0.0, 0.0, rng).equals(p, 1e-12));

  CHECK_FALSE(refine::MakeSimVariant("small_office", 1, 7, "kinect").sensor_options().AnyColour());
  const scene::SimScene real = refine::MakeSimVariant("small_office", 1, 7, "realistic");
  CHECK(real.sensor_options().AnyColour());
  CHECK(real.sensor_options().MotionBlur());
  o.sensor = "realistic";
  const auto blurred = refine::MakeSimScenes(o);
  CHECK(cv::norm(blurred[1].frames.frames[1].rgb, exact[1].frames.frames[1].rgb, cv::NORM_L1) > 0.0);
  o.sensor = "kinect";
  o.pixel_samples = 3;  // the same scenes, each pixel's colour averaged over its area
  const auto area = refine::MakeSimScenes(o);
  CHECK(area[0].frames.frames[0].rgb.size() == exact[0].frames.frames[0].rgb.size());
  CHECK(cv::norm(area[0].frames.frames[0].rgb, exact[0].frames.frames[0].rgb, cv::NORM_L1) > 0.0);
  CHECK(refine::MakeSimVariant("small_office", 0, 7, "kinect", 3).sensor_options().pixel_samples == 3);
  o.pixel_samples = 2;
  CHECK_THROWS_WITH(refine::MakeSimScenes(o), Catch::Contains("pixel_samples"));
  o.pixel_samples = 1;
  o.sensor = "kinekt";
  CHECK_THROWS_WITH(refine::MakeSimScenes(o), Catch::Contains("kinekt"));
  o.sensor = "kinect";
  o.pose_noise_m = -1.0;
  CHECK_THROWS_AS(refine::MakeSimScenes(o), std::invalid_argument);
}
