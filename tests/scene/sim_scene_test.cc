#include "scene/sim_scene.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "scene/sim_builtin_scenes.h"
#include "scene/trajectory.h"
#include "tests/read_file.h"
#include "tests/test_paths.h"

using p2i::scene::CameraInfo;
using p2i::scene::LookAt;
using p2i::scene::LookYawPitch;
using p2i::scene::Pose;
using p2i::scene::RgbdSample;
using p2i::scene::SimScene;
using p2i::scene::SimSceneDescription;
using p2i::scene::SimSensorOptions;
using p2i::scene::SimTexture;

using p2i::testing::ReadFile;

namespace {

CameraInfo MakeCamera(int w, int h, double f, double cx, double cy) {
  return CameraInfo::Pinhole(w, h, f, f, cx, cy);
}

bool SamePixels(const RgbdSample& a, const RgbdSample& b) {
  return cv::norm(a.rgb, b.rgb, cv::NORM_INF) == 0.0 &&
         cv::norm(a.depth, b.depth, cv::NORM_INF) == 0.0;
}

// A 4 m x 4 m x 3 m empty room, optionally with one box 0.6 m wide (y) whose front face is at
// x = 1.25: a camera at the origin looking along +x sees the wall at x = 2 at depth 2.
const char* kTestRoom = R"(
name: test_room
room: {size: [4.0, 4.0, 3.0], floor: grey, ceiling: grey, walls: grey}
materials:
  grey: {texture: solid, color: [0.5, 0.5, 0.5]}
  red: {texture: solid, color: [0.8, 0.1, 0.1]}
lights:
  - {type: point, position: [0.0, 0.0, 2.9]}
)";

std::string WithBox() {
  return std::string(kTestRoom) +
         "objects:\n  - {name: b, shape: box, center: [1.5, 0.0, 1.5], size: [0.5, 0.6, 0.8], "
         "material: red}\n";
}

double GradientEnergy(const cv::Mat& rgb) {
  cv::Mat grey, gx, gy;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  cv::Sobel(grey, gx, CV_32F, 1, 0);
  cv::Sobel(grey, gy, CV_32F, 0, 1);
  cv::Mat mag;
  cv::magnitude(gx, gy, mag);
  return cv::mean(mag)[0];
}

// Looks from the arm zone of the small office towards the poster on the +y wall.
Pose PosterView() { return LookAt({0.5, -1.0, 1.5}, {0.8, 2.5, 1.6}); }

}  // namespace

TEST_CASE("SimScene renders the same pixels twice and across instances", "[unit]") {
  const auto camera = MakeCamera(160, 120, 146.0, 79.5, 59.5);
  const SimScene a = SimScene::BuiltIn("small_office");
  const SimScene b = SimScene::BuiltIn("small_office");
  const Pose pose = PosterView();
  const RgbdSample first = a.Render(pose, camera);
  CHECK(first.rgb.type() == CV_8UC3);
  CHECK(first.depth.type() == CV_32FC1);
  CHECK(first.rgb.cols == 160);
  CHECK(first.rgb.rows == 120);
  CHECK(SamePixels(first, a.Render(pose, camera)));
  CHECK(SamePixels(first, b.Render(pose, camera)));
  CHECK(first.pose.equals(pose));
}

TEST_CASE("SimScene depth is z-depth in metres: a wall 2 m ahead", "[unit]") {
  const SimScene scene = SimScene::FromYamlString(kTestRoom, "test_room");
  // cx, cy on pixel centres so pixel (32, 24) is exactly on the optical axis.
  const auto camera = MakeCamera(65, 49, 40.0, 32.0, 24.0);
  const RgbdSample s = scene.Render(LookYawPitch({0.0, 0.0, 1.5}, 0.0, 0.0), camera);
  CHECK(s.depth.at<float>(24, 32) == Approx(2.0).margin(1e-3));
  // Off-axis pixels on the same wall have the same z-depth (their range is longer).
  CHECK(s.depth.at<float>(10, 5) == Approx(2.0).margin(1e-3));
  CHECK(s.depth.at<float>(40, 60) == Approx(2.0).margin(1e-3));
  // Turned by 30 degrees, the on-axis range to the wall is 2 / cos(30) (z-depth on the axis).
  const RgbdSample t = scene.Render(LookYawPitch({0.0, 0.0, 1.5}, 30.0, 0.0), camera);
  CHECK(t.depth.at<float>(24, 32) == Approx(2.0 / std::cos(M_PI / 6)).margin(1e-3));
}

TEST_CASE("SimScene places a box edge at its projected pixel", "[unit]") {
  const SimScene scene = SimScene::FromYamlString(WithBox(), "box_room");
  const double f = 101.3, cx = 80.0, cy = 60.0;
  const auto camera = MakeCamera(161, 121, f, cx, cy);
  const RgbdSample s = scene.Render(LookYawPitch({0.0, 0.0, 1.5}, 0.0, 0.0), camera);
  // Looking along +x, camera x is world -y: the box's +y edge (y = 0.3) at depth 1.25 projects to
  // u = cx - f * 0.3 / 1.25; its top edge (z = 1.9, 0.4 above the eye) to v = cy - f * 0.4 / 1.25.
  const double u_edge = cx - f * 0.3 / 1.25;
  const double v_edge = cy - f * 0.4 / 1.25;
  REQUIRE(std::abs(u_edge - std::round(u_edge)) > 0.2);
  REQUIRE(std::abs(v_edge - std::round(v_edge)) > 0.2);
  const int row = static_cast<int>(cy), col = static_cast<int>(cx);
  CHECK(s.depth.at<float>(row, static_cast<int>(std::floor(u_edge))) == Approx(2.0).margin(1e-3));
  CHECK(s.depth.at<float>(row, static_cast<int>(std::ceil(u_edge))) == Approx(1.25).margin(1e-3));
  CHECK(s.depth.at<float>(static_cast<int>(std::floor(v_edge)), col) == Approx(2.0).margin(1e-3));
  CHECK(s.depth.at<float>(static_cast<int>(std::ceil(v_edge)), col) == Approx(1.25).margin(1e-3));
  // The box is red, the wall grey.
  const cv::Vec3b box = s.rgb.at<cv::Vec3b>(row, col);
  CHECK(box[0] > 2 * box[1]);
  const cv::Vec3b wall = s.rgb.at<cv::Vec3b>(row, 5);
  CHECK(std::abs(wall[0] - wall[1]) <= 1);
}

TEST_CASE("SimScene gives sane output inside an object and looking at nothing", "[unit]") {
  const SimScene scene = SimScene::FromYamlString(WithBox(), "box_room");
  const auto camera = MakeCamera(64, 48, 50.0, 31.5, 23.5);
  const auto sane = [](const RgbdSample& s) {
    double lo, hi;
    cv::minMaxLoc(s.depth, &lo, &hi);
    return cv::checkRange(s.depth) && lo >= 0.0 && hi < 100.0;
  };
  // Inside the box: its faces are culled, the room around it is seen.
  const RgbdSample inside = scene.Render(LookYawPitch({1.5, 0.0, 1.5}, 0.0, 0.0), camera);
  CHECK(sane(inside));
  CHECK(cv::countNonZero(inside.depth) == 64 * 48);
  // Outside the room looking away from it: nothing at all.
  const RgbdSample away = scene.Render(LookYawPitch({10.0, 0.0, 1.5}, 0.0, 0.0), camera);
  CHECK(sane(away));
  CHECK(cv::countNonZero(away.depth) == 0);
  CHECK(cv::norm(away.rgb, cv::NORM_INF) == 0.0);
  // Straight down and straight up are fine too (no NaN from degenerate rays).
  const RgbdSample down = scene.Render(
      Pose({0.0, 0.0, 1.5}, Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()))),
      camera);
  CHECK(sane(down));
  CHECK(down.depth.at<float>(23, 31) == Approx(1.5).margin(0.02));
  CHECK_THROWS_AS(scene.Render(Pose(), MakeCamera(0, 48, 50.0, 0.0, 0.0)), std::invalid_argument);
}

TEST_CASE("SimScene textures carry fine detail", "[unit]") {
  const auto camera = MakeCamera(320, 240, 292.0, 159.5, 119.5);
  const SimScene textured = SimScene::BuiltIn("small_office");
  SimSceneDescription flat_desc = textured.description();
  for (auto& m : flat_desc.materials) m.texture = SimTexture::kSolid;
  const SimScene flat(flat_desc);
  const double e_textured = GradientEnergy(textured.Render(PosterView(), camera).rgb);
  const double e_flat = GradientEnergy(flat.Render(PosterView(), camera).rgb);
  INFO("gradient energy textured " << e_textured << ", solid " << e_flat);
  CHECK(e_textured > 20.0);
  CHECK(e_textured > 3.0 * e_flat);
}

TEST_CASE("SimScene: two nearby poses give different images", "[unit]") {
  const auto camera = MakeCamera(160, 120, 146.0, 79.5, 59.5);
  const SimScene scene = SimScene::BuiltIn("small_office");
  const Pose a = PosterView();
  const Pose b(a.translation() + Eigen::Vector3d(0.01, 0.0, 0.0), a.rotation());
  const RgbdSample sa = scene.Render(a, camera), sb = scene.Render(b, camera);
  CHECK(cv::norm(sa.rgb, sb.rgb, cv::NORM_L1) > 1000.0);
  CHECK(cv::norm(sa.depth, sb.depth, cv::NORM_INF) > 0.0);
}

TEST_CASE("SimScene sensor effects change pixels only when on, and are seeded", "[unit]") {
  const auto camera = MakeCamera(160, 120, 146.0, 79.5, 59.5);
  SimScene scene = SimScene::BuiltIn("small_office");
  CHECK_FALSE(scene.sensor_options().AnyEnabled());
  const Pose pose = LookYawPitch({0.0, -1.5, 1.3}, 80.0, -10.0);
  const RgbdSample clean = scene.Render(pose, camera);

  SimSensorOptions off;
  off.seed = 99;  // a seed alone enables nothing
  scene.set_sensor_options(off);
  CHECK(SamePixels(clean, scene.Render(pose, camera)));
  CHECK(SamePixels(clean, scene.Render(pose, camera, 3.0)));  // the stamp alone changes nothing

  scene.set_sensor_options(SimSensorOptions::Kinect(7));
  const RgbdSample noisy = scene.Render(pose, camera);
  CHECK(cv::norm(clean.rgb, noisy.rgb, cv::NORM_INF) > 0.0);
  CHECK(cv::norm(clean.depth, noisy.depth, cv::NORM_INF) > 0.0);
  CHECK(SamePixels(noisy, scene.Render(pose, camera)));  // same seed, same pixels
  SimScene other = SimScene::BuiltIn("small_office");
  other.set_sensor_options(SimSensorOptions::Kinect(7));
  CHECK(SamePixels(noisy, other.Render(pose, camera)));
  other.set_sensor_options(SimSensorOptions::Kinect(8));
  CHECK_FALSE(SamePixels(noisy, other.Render(pose, camera)));
  // Stamped frames: fresh noise per stamp, reproducible per stamp, stamp carried.
  const RgbdSample at1 = scene.Render(pose, camera, 1.0);
  CHECK(at1.stamp == 1.0);
  CHECK(SamePixels(at1, scene.Render(pose, camera, 1.0)));
  CHECK_FALSE(SamePixels(at1, scene.Render(pose, camera, 1.05)));

  // Far range: everything beyond max_range becomes a hole, nothing else changes.
  SimSensorOptions far;
  far.max_range = 3.0;
  scene.set_sensor_options(far);
  const RgbdSample clipped = scene.Render(pose, camera);
  int beyond = 0, mismatched = 0;
  for (int v = 0; v < clean.depth.rows; ++v) {
    for (int u = 0; u < clean.depth.cols; ++u) {
      const float z = clean.depth.at<float>(v, u), c = clipped.depth.at<float>(v, u);
      if (z > 3.0f) {
        ++beyond;
        if (c != 0.0f) ++mismatched;
      } else if (c != z) {
        ++mismatched;
      }
    }
  }
  CHECK(beyond > 100);
  CHECK(mismatched == 0);
  CHECK(SamePixels(RgbdSample{0, {}, clean.rgb, clipped.depth, ""}, clipped));

  // Grazing angles: a camera looking along a wall loses the far, grazing part of the floor.
  SimSensorOptions grazing;
  grazing.grazing_angle_deg = 70.0;
  scene.set_sensor_options(grazing);
  const RgbdSample holes = scene.Render(pose, camera);
  CHECK(cv::countNonZero(holes.depth) < cv::countNonZero(clean.depth));
}

TEST_CASE("SimScene renders from several threads at once", "[unit]") {
  const auto camera = MakeCamera(96, 72, 88.0, 47.5, 35.5);
  const SimScene scene = SimScene::BuiltIn("large_office");
  const Pose p1 = LookYawPitch({0.0, -1.5, 1.3}, 90.0, 0.0);
  const Pose p2 = LookYawPitch({0.5, 0.5, 1.0}, 200.0, -20.0);
  const RgbdSample r1 = scene.Render(p1, camera), r2 = scene.Render(p2, camera);
  RgbdSample t1, t2;
  std::thread a([&] {
    for (int i = 0; i < 5; ++i) t1 = scene.Render(p1, camera);
  });
  std::thread b([&] {
    for (int i = 0; i < 5; ++i) t2 = scene.Render(p2, camera);
  });
  a.join();
  b.join();
  CHECK(SamePixels(r1, t1));
  CHECK(SamePixels(r2, t2));
}

TEST_CASE("SimScene built-in scenes equal the shipped YAML files and parse", "[unit]") {
  REQUIRE(p2i::scene::BuiltInSceneNames().size() == 2);
  for (const auto& name : SimScene::BuiltInNames()) {
    const std::string path = p2i::testing::SourceDir() + "/scene/scenes/" + name + ".yaml";
    INFO(path << " differs from the embedded copy: run python3 scene/scenes/embed_scenes.py");
    CHECK(SimScene::BuiltInYaml(name) == ReadFile(path));
    const SimScene from_file = SimScene::FromYamlFile(path);
    CHECK(from_file.description().name == name);
    CHECK(from_file.description().objects.size() >= 20);
  }
  CHECK(SimScene::BuiltIn("large_office").description().objects.size() >
        SimScene::BuiltIn("small_office").description().objects.size());
  CHECK(SimScene::BuiltIn("large_office").Bounds().max.x() >
        SimScene::BuiltIn("small_office").Bounds().max.x());
  CHECK_THROWS_WITH(SimScene::BuiltIn("kitchen"), Catch::Contains("small_office"));
}

TEST_CASE("SimScene YAML errors name the source, line and key", "[unit]") {
  const auto error_of = [](const std::string& text) {
    try {
      SimScene::FromYamlString(text, "my_scene.yaml");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // Unknown key on line 6.
  std::string text = kTestRoom;
  text +=
      "objects:\n  - {name: b, shape: box, center: [0, 0, 1], size: [1, 1, 1], material: red,"
      " colour: [1, 0, 0]}\n";
  const std::string unknown = error_of(text);
  CHECK_THAT(unknown, Catch::Contains("my_scene.yaml:10") && Catch::Contains("colour"));
  CHECK_THAT(error_of(std::string(kTestRoom) + "lightz: []\n"),
             Catch::Contains("my_scene.yaml:9") && Catch::Contains("lightz"));
  CHECK_THAT(
      error_of(std::string(kTestRoom) +
               "objects:\n  - {shape: box, center: [0, 0, 1], size: [1, 1, 1], material: blue}\n"),
      Catch::Contains("unknown material 'blue'"));
  CHECK_THAT(error_of("name: x\nmaterials: {a: {texture: marble}}\nroom: {size: [1, 1, 1], "
                      "floor: a, ceiling: a, walls: a}\n"),
             Catch::Contains("my_scene.yaml:2") && Catch::Contains("marble"));
  CHECK_THAT(error_of("name: x\nmaterials: {a: {}}\nroom: {size: [1, -1, 1], floor: a, "
                      "ceiling: a, walls: a}\n"),
             Catch::Contains("room size"));
  CHECK_THAT(error_of("name: [x\n"), Catch::Contains("my_scene.yaml") && Catch::Contains("syntax"));
  CHECK_THROWS_WITH(SimScene::FromYamlFile("/nonexistent/scene.yaml"),
                    Catch::Contains("/nonexistent/scene.yaml"));
}

TEST_CASE("SimScene IsFree knows the room and its objects", "[unit]") {
  const SimScene scene = SimScene::FromYamlString(WithBox(), "box_room");
  CHECK(scene.IsFree({0.0, 0.0, 1.5}));
  CHECK_FALSE(scene.IsFree({1.5, 0.0, 1.5}));       // inside the box
  CHECK_FALSE(scene.IsFree({1.1, 0.0, 1.5}, 0.2));  // within clearance of its face
  CHECK(scene.IsFree({1.1, 0.0, 1.5}, 0.1));
  CHECK_FALSE(scene.IsFree({0.0, 0.0, 3.5}));        // above the ceiling
  CHECK_FALSE(scene.IsFree({1.95, 0.0, 1.0}, 0.1));  // too close to the wall
  CHECK(scene.Bounds().max.z() == Approx(3.0));
}

TEST_CASE("SimScene sensor noise has the configured spread", "[unit]") {
  SimScene scene = SimScene::FromYamlString(kTestRoom, "test_room");
  const auto camera = MakeCamera(64, 48, 40.0, 31.5, 23.5);
  const Pose pose = LookYawPitch({0.0, 0.0, 1.5}, 0.0, 0.0);  // the wall at x = 2 fills the view
  const RgbdSample clean = scene.Render(pose, camera);
  SimSensorOptions o;
  o.depth_noise_sigma = 0.01;
  o.rgb_noise_sigma = 5.0;
  o.seed = 5;
  scene.set_sensor_options(o);
  const RgbdSample noisy = scene.Render(pose, camera);
  cv::Mat depth_diff = noisy.depth - clean.depth;
  cv::Mat rgb_diff;
  cv::subtract(noisy.rgb, clean.rgb, rgb_diff, cv::noArray(), CV_32FC3);
  cv::Scalar mean, stddev;
  cv::meanStdDev(depth_diff, mean, stddev);
  CHECK(std::abs(mean[0]) < 0.002);
  CHECK(stddev[0] == Approx(0.01).epsilon(0.15));
  cv::meanStdDev(rgb_diff.reshape(1), mean, stddev);
  CHECK(std::abs(mean[0]) < 0.5);
  CHECK(stddev[0] == Approx(5.0).epsilon(0.15));
}

namespace {

// The world point seen by the brightest pixel of `highlight` (a grey image), from its depth.
Eigen::Vector3d BrightestPoint(const cv::Mat& highlight, const RgbdSample& s,
                               const CameraInfo& camera, double* peak) {
  cv::Point at;
  cv::minMaxLoc(highlight, nullptr, peak, nullptr, &at);
  const double z = s.depth.at<float>(at.y, at.x);
  const Eigen::Vector3d p_cam((at.x - camera.cx()) / camera.fx() * z,
                              (at.y - camera.cy()) / camera.fy() * z, z);
  return s.pose * p_cam;
}

}  // namespace

TEST_CASE("SimScene specular highlight sits at the light's mirror point and moves with the view",
          "[unit]") {
  // A glossy floor under one point light at (0, 0, 2.9): seen from C, the highlight is where the
  // ray from the mirror image of C (below the floor) to the light crosses the floor.
  const SimScene scene = SimScene::FromYamlString(R"(
room: {size: [4.0, 4.0, 3.0], floor: glossy, ceiling: grey, walls: grey}
materials:
  grey: {texture: solid, color: [0.5, 0.5, 0.5]}
  glossy: {texture: solid, color: [0.3, 0.3, 0.3], specular: 1.0, shininess: 200}
lights:
  - {type: point, position: [0.0, 0.0, 2.9]}
)",
                                                   "glossy_room");
  REQUIRE(scene.description().AnyViewDependent());
  const SimScene matte = scene.Lambertian();
  CHECK_FALSE(matte.description().AnyViewDependent());
  const auto camera = MakeCamera(160, 120, 120.0, 79.5, 59.5);
  const Eigen::Vector3d light(0.0, 0.0, 2.9);

  std::vector<Eigen::Vector3d> found;
  for (const Eigen::Vector3d& eye : {Eigen::Vector3d(-1.2, -1.0, 1.3), Eigen::Vector3d(1.0, -1.4, 1.0)}) {
    const Eigen::Vector3d mirror(eye.x(), eye.y(), -eye.z());
    const Eigen::Vector3d expected = mirror + (light - mirror) * (eye.z() / (eye.z() + light.z()));
    const Pose pose = LookAt(eye, expected);
    const RgbdSample shiny = scene.Render(pose, camera), flat = matte.Render(pose, camera);
    CHECK(cv::norm(shiny.depth, flat.depth, cv::NORM_INF) == 0.0);  // geometry unchanged
    cv::Mat diff;
    cv::subtract(shiny.rgb, flat.rgb, diff, cv::noArray(), CV_32FC3);
    cv::cvtColor(diff, diff, cv::COLOR_RGB2GRAY);
    double peak = 0;
    const Eigen::Vector3d at = BrightestPoint(diff, shiny, camera, &peak);
    INFO("eye " << eye.transpose() << " expected " << expected.transpose() << " found "
                << at.transpose() << " peak " << peak);
    CHECK(peak > 40.0);                         // a visible highlight
    CHECK((at - expected).norm() < 0.05);       // at the mirror point
    CHECK(cv::mean(diff)[0] < 0.2 * peak);      // a highlight, not a uniform brightening
    found.push_back(at);
  }
  CHECK((found[0] - found[1]).norm() > 0.5);  // it moved with the view
}

TEST_CASE("SimScene large office has view-dependent materials, Lambertian() removes them",
          "[unit]") {
  const SimScene scene = SimScene::BuiltIn("large_office");
  CHECK(scene.description().AnyViewDependent());
  CHECK_FALSE(SimScene::BuiltIn("small_office").description().AnyViewDependent());
  const auto camera = MakeCamera(80, 60, 60.0, 39.5, 29.5);
  const Pose floor_view = LookAt({0.0, -1.5, 1.3}, {0.77, -1.19, 0.0});
  const RgbdSample shiny = scene.Render(floor_view, camera);
  const RgbdSample flat = scene.Lambertian().Render(floor_view, camera);
  CHECK(cv::mean(shiny.rgb)[1] > cv::mean(flat.rgb)[1] + 5.0);
}
