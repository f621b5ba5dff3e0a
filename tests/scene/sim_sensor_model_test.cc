// The simulated sensor's colour pipeline and motion blur (scene/sim_sensor_model.h, SimScene):
// each effect changes the statistics it is specified to change, only when on, reproducibly per
// seed and stamp.
#include "scene/sim_sensor_model.h"

#include <yaml-cpp/yaml.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "scene/sim_scene.h"
#include "scene/trajectory.h"

using p2i::scene::CameraInfo;
using p2i::scene::LookAt;
using p2i::scene::LookYawPitch;
using p2i::scene::Pose;
using p2i::scene::RgbdSample;
using p2i::scene::SimScene;
using p2i::scene::SimSensorOptions;
using p2i::scene::StampedPose;

namespace {

const char* kGreyRoom = R"(
name: grey_room
room: {size: [4.0, 4.0, 3.0], floor: grey, ceiling: grey, walls: grey}
materials:
  grey: {texture: solid, color: [0.5, 0.5, 0.5]}
lights:
  - {type: point, position: [0.0, 0.0, 2.9]}
)";

CameraInfo Camera() { return CameraInfo::Pinhole(64, 48, 40.0, 40.0, 31.5, 23.5); }
Pose WallView() { return LookYawPitch({0.0, 0.0, 1.5}, 0.0, 0.0); }

bool SamePixels(const RgbdSample& a, const RgbdSample& b) {
  return cv::norm(a.rgb, b.rgb, cv::NORM_INF) == 0.0 &&
         cv::norm(a.depth, b.depth, cv::NORM_INF) == 0.0;
}

cv::Scalar MeanRgb(const RgbdSample& s) { return cv::mean(s.rgb); }

double GradientEnergy(const cv::Mat& rgb) {
  cv::Mat grey, gx, gy, mag;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  cv::Sobel(grey, gx, CV_32F, 1, 0);
  cv::Sobel(grey, gy, CV_32F, 0, 1);
  cv::magnitude(gx, gy, mag);
  return cv::mean(mag)[0];
}

}  // namespace

TEST_CASE("Sensor auto-exposure brings each frame's mean luminance towards the target",
          "[unit]") {
  SimScene scene = SimScene::FromYamlString(kGreyRoom, "grey_room");
  const Pose bright = LookYawPitch({0.0, 0.0, 1.5}, 0.0, -60.0);  // the floor under the light
  const Pose dark = LookYawPitch({0.0, 0.0, 2.2}, 0.0, 60.0);     // the ceiling, lit edge-on
  const double clean_bright = MeanRgb(scene.Render(bright, Camera()))[1];
  const double clean_dark = MeanRgb(scene.Render(dark, Camera()))[1];
  REQUIRE(clean_bright > clean_dark + 10.0);

  SimSensorOptions o;
  o.auto_exposure = 1.0;
  o.exposure_target = 0.3;
  scene.set_sensor_options(o);
  // Full strength: both frames end at the target (grey surfaces: luminance = every channel).
  CHECK(MeanRgb(scene.Render(bright, Camera()))[1] == Approx(0.3 * 255).margin(1.5));
  CHECK(MeanRgb(scene.Render(dark, Camera()))[1] == Approx(0.3 * 255).margin(1.5));
  // Half strength: gain = (target / mean)^0.5.
  o.auto_exposure = 0.5;
  scene.set_sensor_options(o);
  const double expected = clean_dark * std::sqrt(0.3 * 255 / clean_dark);
  CHECK(MeanRgb(scene.Render(dark, Camera()))[1] == Approx(expected).epsilon(0.02));
}

TEST_CASE("Sensor exposure drift is smooth in time, bounded by its amplitude and seeded",
          "[unit]") {
  SimScene scene = SimScene::FromYamlString(kGreyRoom, "grey_room");
  const double clean = MeanRgb(scene.Render(WallView(), Camera()))[1];
  SimSensorOptions o;
  o.exposure_drift = 0.1;
  o.seed = 3;
  scene.set_sensor_options(o);
  double lo = 10, hi = 0, max_step = 0;
  double previous = -1;
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.05 * k;  // 10 s at 20 frames/s
    const double ratio = MeanRgb(scene.Render(WallView(), Camera(), t))[1] / clean;
    lo = std::min(lo, ratio), hi = std::max(hi, ratio);
    if (previous > 0) max_step = std::max(max_step, std::abs(ratio - previous));
    previous = ratio;
  }
  CHECK(lo >= 0.9 - 0.01);
  CHECK(hi <= 1.1 + 0.01);
  CHECK(hi - lo > 0.1);      // it does drift, over a good part of its range
  CHECK(max_step < 0.012);  // slowly: frames 50 ms apart differ by about 1 %
  const RgbdSample at = scene.Render(WallView(), Camera(), 2.5);
  CHECK(SamePixels(at, scene.Render(WallView(), Camera(), 2.5)));
  o.seed = 4;
  SimScene other = SimScene::FromYamlString(kGreyRoom, "grey_room");
  other.set_sensor_options(o);
  CHECK_FALSE(SamePixels(at, other.Render(WallView(), Camera(), 2.5)));
}

TEST_CASE("Sensor white-balance drift moves red and blue, not green", "[unit]") {
  SimScene scene = SimScene::FromYamlString(kGreyRoom, "grey_room");
  const RgbdSample clean = scene.Render(WallView(), Camera());
  SimSensorOptions o;
  o.white_balance_drift = 0.05;
  o.seed = 1;
  scene.set_sensor_options(o);
  double r_lo = 10, r_hi = 0, b_lo = 10, b_hi = 0;
  for (int k = 0; k <= 40; ++k) {
    const RgbdSample s = scene.Render(WallView(), Camera(), 0.25 * k);
    std::vector<cv::Mat> a, b;
    cv::split(s.rgb, a);
    cv::split(clean.rgb, b);
    CHECK(cv::norm(a[1], b[1], cv::NORM_INF) == 0.0);  // green gain stays 1
    CHECK(cv::norm(s.depth, clean.depth, cv::NORM_INF) == 0.0);
    const double r = cv::mean(a[0])[0] / cv::mean(b[0])[0];
    const double bl = cv::mean(a[2])[0] / cv::mean(b[2])[0];
    r_lo = std::min(r_lo, r), r_hi = std::max(r_hi, r);
    b_lo = std::min(b_lo, bl), b_hi = std::max(b_hi, bl);
  }
  CHECK(r_lo >= 0.95 - 0.01);
  CHECK(r_hi <= 1.05 + 0.01);
  CHECK(b_lo >= 0.95 - 0.01);
  CHECK(b_hi <= 1.05 + 0.01);
  CHECK(r_hi - r_lo > 0.03);
  CHECK(b_hi - b_lo > 0.03);
}

TEST_CASE("Sensor motion blur smears RGB along the motion and drops mixed depth", "[unit]") {
  SimScene scene = SimScene::BuiltIn("small_office");
  const auto camera = SimScene::DefaultCamera(160, 120);
  // A fast pan (60 degrees/s) past furniture edges.
  std::vector<StampedPose> pan;
  for (int k = 0; k < 21; ++k) {
    pan.push_back({0.05 * k, LookYawPitch({0.0, -1.5, 1.3}, 70.0 + 3.0 * k, -10.0)});
  }
  const RgbdSample sharp = scene.RenderOnTrajectory(pan, 10, camera);
  SimSensorOptions o;
  o.exposure_time_s = 0.04;  // 2.4 degrees of pan while the shutter is open (~7 px)
  o.motion_blur_samples = 6;
  scene.set_sensor_options(o);
  const RgbdSample blurred = scene.RenderOnTrajectory(pan, 10, camera);
  CHECK(blurred.stamp == 0.5);
  CHECK(blurred.pose.equals(pan[10].pose));
  CHECK(GradientEnergy(blurred.rgb) < 0.8 * GradientEnergy(sharp.rgb));
  CHECK(cv::mean(blurred.rgb)[1] == Approx(cv::mean(sharp.rgb)[1]).epsilon(0.03));
  // Depth: the frame pose's own depth, with holes only where the surface changed.
  int holes = 0, changed = 0;
  for (int v = 0; v < sharp.depth.rows; ++v) {
    for (int u = 0; u < sharp.depth.cols; ++u) {
      const float z = sharp.depth.at<float>(v, u), b = blurred.depth.at<float>(v, u);
      if (b == 0.0f && z > 0.0f) ++holes;
      if (b != 0.0f && b != z) ++changed;
    }
  }
  CHECK(holes > 20);
  CHECK(holes < static_cast<int>(sharp.depth.total() / 5));
  CHECK(changed == 0);
  CHECK(SamePixels(blurred, scene.RenderOnTrajectory(pan, 10, camera)));  // deterministic
  // No motion while the shutter is open: no blur.
  const p2i::scene::SimExposure still{pan[10].pose, pan[10].pose};
  CHECK(SamePixels(sharp, scene.Render(pan[10].pose, camera, 0.5, still)));
  // The shutter poses lie on the trajectory, centred on the frame, held at its ends.
  const auto e = p2i::scene::ExposureOnTrajectory(pan, 10, 0.04);
  CHECK(Pose::RotationDistanceDeg(e.open, pan[10].pose) == Approx(1.2).epsilon(0.01));
  CHECK(Pose::RotationDistanceDeg(e.close, pan[10].pose) == Approx(1.2).epsilon(0.01));
  CHECK(p2i::scene::ExposureOnTrajectory(pan, 0, 0.04).open.equals(pan[0].pose));
}

TEST_CASE("Sensor presets and YAML: realistic turns every effect on, errors name key and value",
          "[unit]") {
  const SimSensorOptions r = SimSensorOptions::Realistic(5);
  CHECK(r.AnyNoise());
  CHECK(r.AnyColour());
  CHECK(r.MotionBlur());
  CHECK(r.seed == 5);
  CHECK_FALSE(SimSensorOptions().AnyEnabled());
  CHECK_FALSE(SimSensorOptions::Kinect().AnyColour());
  CHECK(SimSensorOptions::FromPreset("realistic", 5).auto_exposure == r.auto_exposure);
  CHECK(SimSensorOptions::FromPreset("realistic", 5).seed == 5);
  CHECK(SimSensorOptions::FromPreset("kinect", 2).AnyNoise());
  CHECK_FALSE(SimSensorOptions::FromPreset("kinect", 2).AnyColour());
  CHECK_FALSE(SimSensorOptions::FromPreset("none", 2).AnyEnabled());
  CHECK_THROWS_WITH(SimSensorOptions::FromPreset("fancy"), Catch::Contains("'fancy'"));

  const auto o = SimSensorOptions::FromYaml(
      YAML::Load("{preset: realistic, seed: 3, exposure_time_s: 0.01, motion_blur_samples: 3}"),
      "cfg.yaml");
  CHECK(o.seed == 3);
  CHECK(o.exposure_time_s == 0.01);
  CHECK(o.motion_blur_samples == 3);
  CHECK(o.auto_exposure == r.auto_exposure);
  CHECK(o.max_range == 4.5);

  const auto fails_with = [](const char* text, const char* what) {
    try {
      (void)SimSensorOptions::FromYaml(YAML::Load(text), "cfg.yaml");
      FAIL("no error for " << text);
    } catch (const std::runtime_error& e) {
      INFO(e.what());
      CHECK(std::string(e.what()).find("cfg.yaml:1") == 0);
      CHECK(std::string(e.what()).find(what) != std::string::npos);
    }
  };
  fails_with("{exposure_drift_amp: 0.1}", "unknown key 'exposure_drift_amp'");
  fails_with("{auto_exposure: 1.5}", "auto_exposure must be at most 1 (got 1.5)");
  fails_with("{exposure_target: 0}", "exposure_target must be in (0, 1] (got 0)");
  fails_with("{motion_blur_samples: 0}", "motion_blur_samples must be in [1, 64] (got 0)");
  fails_with("{depth_dropout: -0.1}", "depth_dropout must be finite and >= 0 (got -0.1)");
  fails_with("{preset: fancy}", "unknown preset 'fancy'");
}

TEST_CASE("Sensor pixel area: colour averaged over the pixel, depth of the centre ray", "[unit]") {
  const SimScene base = SimScene::BuiltIn("small_office");
  const CameraInfo cam = CameraInfo::Pinhole(48, 36, 30.0, 30.0, 23.5, 17.5);
  const Pose pose = LookAt({0.5, -1.0, 1.5}, {0.8, 2.5, 1.6});  // the poster wall
  const auto render = [&](int n) {
    SimSensorOptions o;
    o.pixel_samples = n;
    return SimScene(base.description(), o).Render(pose, cam);
  };
  const RgbdSample one = render(1), three = render(3), seven = render(7);
  CHECK_FALSE(SimSensorOptions().PixelArea());
  CHECK(SimSensorOptions::Realistic().pixel_samples == 1);  // earlier bench runs reproduce
  // Depth comes from the centre ray: the same as the one-ray render up to float rounding.
  REQUIRE(cv::countNonZero(one.depth > 0) == cv::countNonZero(three.depth > 0));
  CHECK(cv::norm(one.depth, three.depth, cv::NORM_INF) < 1e-3);  // 1 mm; an off-centre ray: cm
  CHECK(cv::norm(one.depth, seven.depth, cv::NORM_INF) < 1e-3);
  // Colour converges as the pixel's area is sampled more finely: 3x3 is much nearer to 7x7 than
  // the centre ray is, and the image is smoother (less aliasing of the textures).
  const double psnr_one = cv::PSNR(one.rgb, seven.rgb), psnr_three = cv::PSNR(three.rgb, seven.rgb);
  INFO("PSNR against 7x7: 1 ray " << psnr_one << " dB, 3x3 " << psnr_three << " dB");
  CHECK(psnr_three > psnr_one + 3.0);
  CHECK(GradientEnergy(three.rgb) < GradientEnergy(one.rgb));
  // Mean colour is kept (no brightening or darkening by the averaging).
  for (int c = 0; c < 3; ++c) CHECK(std::abs(MeanRgb(one)[c] - MeanRgb(three)[c]) < 3.0);

  SimSensorOptions even;
  even.pixel_samples = 2;
  CHECK_THROWS_WITH(even.Validate(), Catch::Contains("pixel_samples must be odd"));
  CHECK(SimSensorOptions::FromYaml(YAML::Load("{pixel_samples: 5}"), "cfg.yaml").pixel_samples == 5);
  CHECK_THROWS_WITH(SimSensorOptions::FromYaml(YAML::Load("{pixel_samples: 4}"), "cfg.yaml"),
                    Catch::Contains("cfg.yaml:1") && Catch::Contains("pixel_samples"));
}

TEST_CASE("SensorDrift is in [-1, 1], seeded per channel", "[unit]") {
  double lo = 2, hi = -2;
  for (int k = 0; k < 2000; ++k) {
    const double d = p2i::scene::SensorDrift(7, 0, 0.01 * k, 8.0);
    lo = std::min(lo, d), hi = std::max(hi, d);
  }
  CHECK(lo >= -1.0);
  CHECK(hi <= 1.0);
  CHECK(hi - lo > 1.0);
  CHECK(p2i::scene::SensorDrift(7, 0, 1.0, 8.0) != p2i::scene::SensorDrift(7, 1, 1.0, 8.0));
  CHECK(p2i::scene::SensorDrift(7, 0, 1.0, 8.0) != p2i::scene::SensorDrift(8, 0, 1.0, 8.0));
  CHECK(p2i::scene::SensorDrift(7, 0, 1.0, 8.0) == p2i::scene::SensorDrift(7, 0, 1.0, 8.0));
}
