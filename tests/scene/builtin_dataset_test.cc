/// @file builtin_dataset_test.cc
/// @brief `builtin:NAME` training data: the default arm sweep, the sim camera, stride and
/// max_frames, poses-only mode, errors.
#include "scene/builtin_dataset.h"

#include <stdexcept>

#include <catch2/catch.hpp>

#include "scene/sim_scene.h"
#include "scene/trajectory.h"

namespace p2i::scene {
namespace {

TEST_CASE("builtin:NAME renders the default arm sweep with the sim camera", "[unit]") {
  const auto sweep = GenerateArmSweep({});
  BuiltinDatasetOptions o;
  o.width = 32;
  o.height = 24;
  o.stride = 50;
  o.with_frames = false;
  const RgbdDataset poses = RenderBuiltinDataset("builtin:small_office", o);
  REQUIRE(poses.frames.size() == (sweep.size() + 49) / 50);
  CHECK(poses.frames[1].id == "sweep/50");
  CHECK(poses.frames[1].pose.equals(sweep[50].pose, 1e-12));
  CHECK(poses.frames[1].rgb.empty());
  const CameraInfo cam = SimScene::DefaultCamera(32, 24);
  CHECK(poses.camera.camera_matrix == cam.camera_matrix);  // f = 525 * 32 / 640

  o.stride = 1;
  o.max_frames = 3;
  o.with_frames = true;
  const RgbdDataset three = RenderBuiltinDataset("builtin:small_office", o);
  REQUIRE(three.frames.size() == 3);
  CHECK(three.frames.front().id == "sweep/0");
  CHECK(three.frames.back().id == "sweep/" + std::to_string(sweep.size() - 1));  // evenly spaced
  CHECK(three.frames[0].rgb.size() == cv::Size(32, 24));
  CHECK(three.frames[0].depth.type() == CV_32FC1);

  CHECK(IsBuiltinSpec("builtin:large_office"));
  CHECK_FALSE(IsBuiltinSpec("/data/builtin:x"));
  CHECK_THROWS_AS(RenderBuiltinDataset("small_office", o), std::invalid_argument);
  CHECK_THROWS(RenderBuiltinDataset("builtin:no_such_office", o));
  o.width = 0;
  CHECK_THROWS_WITH(RenderBuiltinDataset("builtin:small_office", o), Catch::Contains("width"));
}

}  // namespace
}  // namespace p2i::scene
