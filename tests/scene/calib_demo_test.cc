/// @file calib_demo_test.cc
/// @brief calib/sim_64.yaml and sim_128.yaml are exactly the sim camera as 64x64 and 128x128
/// demo views see it.
#include <string>

#include <catch2/catch.hpp>

#include "scene/camera_info.h"
#include "scene/image_ops.h"
#include "tests/test_paths.h"

using p2i::scene::CameraInfo;

namespace {

// calib/NAME.yaml equals sim.yaml centre-cropped and resized to side x side, focal f, centre c.
void CheckCropOfSim(const std::string& name, int side, double f, double c) {
  const std::string dir = p2i::testing::SourceDir() + "/calib/";
  const CameraInfo sim = CameraInfo::FromYamlFile(dir + "sim.yaml");
  CameraInfo expected = p2i::scene::CenterCropResizeCamera(sim, side, side);
  expected.camera_name = name;
  const CameraInfo file = CameraInfo::FromYamlFile(dir + name + ".yaml");
  CHECK(file.equals(expected, 1e-9));
  CHECK(file.fx() == Approx(f));
  CHECK(file.cx() == Approx(c));
}

}  // namespace

TEST_CASE("calib/sim_64.yaml is sim.yaml centre-cropped and resized to 64x64", "[unit]") {
  CheckCropOfSim("sim_64", 64, 70.0, 31.5);
}

TEST_CASE("calib/sim_128.yaml is sim.yaml centre-cropped and resized to 128x128", "[unit]") {
  CheckCropOfSim("sim_128", 128, 140.0, 63.5);
}
