/// @file sim_scene_spec_test.cc
/// @brief SimScene::FromSpec (the scene parameter every node and tool takes) and DefaultCamera.
#include <catch2/catch.hpp>

#include "scene/camera_info.h"
#include "scene/sim_scene.h"
#include "tests/test_paths.h"

using p2i::scene::CameraInfo;
using p2i::scene::Pose;
using p2i::scene::SimScene;

TEST_CASE("SimScene::FromSpec takes builtin:NAME, a bare name or a YAML file", "[unit]") {
  const CameraInfo cam = SimScene::DefaultCamera(32, 24);
  const Pose pose(Eigen::Vector3d(0, 0, 1.2), Eigen::Quaterniond(Eigen::AngleAxisd(
                                                  -M_PI / 2, Eigen::Vector3d::UnitX())));
  const auto ref = SimScene::BuiltIn("large_office").Render(pose, cam);
  for (const std::string& spec :
       {std::string("builtin:large_office"), std::string("large_office"),
        p2i::testing::SourceDir() + "/scene/scenes/large_office.yaml"}) {
    INFO(spec);
    const auto got = SimScene::FromSpec(spec).Render(pose, cam);
    CHECK(cv::norm(got.rgb, ref.rgb, cv::NORM_INF) == 0);
  }
  // A different scene renders differently (the spec is not ignored).
  const auto small = SimScene::FromSpec("builtin:small_office").Render(pose, cam);
  CHECK(cv::norm(small.rgb, ref.rgb, cv::NORM_INF) > 0);
  try {
    SimScene::FromSpec("no_such_scene.yaml");
    FAIL("expected an error");
  } catch (const std::exception& e) {
    CHECK_THAT(e.what(), Catch::Contains("no_such_scene.yaml") &&
                             Catch::Contains("builtin:small_office"));
  }
  CHECK_THROWS(SimScene::FromSpec("builtin:no_such_office"));
}

TEST_CASE("SimScene::DefaultCamera is calib/sim.yaml, scaled to the image size", "[unit]") {
  const CameraInfo file = CameraInfo::FromYamlFile(p2i::testing::SourceDir() + "/calib/sim.yaml");
  CHECK(SimScene::DefaultCamera().equals(file, 1e-12));
  const CameraInfo half = SimScene::DefaultCamera(320, 240);
  CHECK(half.fx() == Approx(262.5));
  CHECK(half.cx() == Approx(159.5));
}
