/// @file calib_demo_test.cc
/// @brief calib/sim_64.yaml is exactly the sim camera as the demo's 64x64 views see it.
#include <catch2/catch.hpp>

#include "scene/camera_info.h"
#include "scene/image_ops.h"
#include "tests/test_paths.h"

using p2i::scene::CameraInfo;

TEST_CASE("calib/sim_64.yaml is sim.yaml centre-cropped and resized to 64x64", "[unit]") {
  const std::string dir = p2i::testing::SourceDir() + "/calib/";
  const CameraInfo sim = CameraInfo::FromYamlFile(dir + "sim.yaml");
  CameraInfo expected = p2i::scene::CenterCropResizeCamera(sim, 64, 64);
  expected.camera_name = "sim_64";
  const CameraInfo file = CameraInfo::FromYamlFile(dir + "sim_64.yaml");
  CHECK(file.equals(expected, 1e-9));
  CHECK(file.fx() == Approx(70.0));
  CHECK(file.cx() == Approx(31.5));
}
