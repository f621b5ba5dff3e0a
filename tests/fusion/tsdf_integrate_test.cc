/// @file tsdf_integrate_test.cc
/// @brief The TSDF's own integration kernel (fusion/tsdf_integrate.h) against Open3D's
/// VoxelBlockGrid::Integrate: the same volume, byte for byte, on noisy sim frames, with the hash
/// map growing on the way, for both block sizes.
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "fusion/tsdf_volume.h"
#include "scene/sim_scene.h"
#include "scene/sim_sensor_options.h"
#include "scene/trajectory.h"
#include "tests/read_file.h"
#include "tests/temp_dir.h"

namespace p2i::fusion {
namespace {

TEST_CASE("TsdfVolume: its own integration kernel fuses noisy frames into the volume Open3D's "
          "kernel fuses, byte for byte",
          "[unit]") {
  const int blocks = GENERATE(8, 16);
  INFO("blocks of " << blocks << "^3");
  // The realistic sensor: depth noise and dropout, colour noise, exposure drift.
  const scene::SimScene sim(scene::SimScene::BuiltIn("small_office").description(),
                            scene::SimSensorOptions::Realistic(7));
  const scene::CameraInfo cam = scene::SimScene::DefaultCamera(160, 120);
  const auto sweep = scene::GenerateArmSweep({});
  TsdfOptions o;
  o.block_resolution = blocks;
  o.initial_blocks = 16;  // the hash map grows several times while the frames go in
  TsdfOptions reference = o;
  reference.integrator = "open3d";
  TsdfVolume own(o), open3d(reference);
  int frames = 0;
  for (size_t i = 0; i < sweep.size(); i += sweep.size() / 6, ++frames) {
    const scene::RgbdSample f = sim.Render(sweep[i].pose, cam, sweep[i].stamp);
    own.Integrate(f, cam);
    open3d.Integrate(f, cam);
  }
  REQUIRE(frames >= 6);
  CHECK(own.Stats().blocks == open3d.Stats().blocks);
  CHECK(own.Stats().blocks > 16);
  CHECK(own.Stats().capacity_blocks > 16);  // it grew
  testing::TempDir dir;
  const std::string a = dir.path() + "/own.npz", b = dir.path() + "/open3d.npz";
  own.Save(a);
  open3d.Save(b);
  const std::string own_bytes = testing::ReadFile(a), open3d_bytes = testing::ReadFile(b);
  REQUIRE(own_bytes.size() > 100000);
  CHECK(own_bytes.size() == open3d_bytes.size());
  CHECK((own_bytes == open3d_bytes));
  // And they render the same view.
  const scene::Pose view = sweep[sweep.size() / 2 + 3].pose;
  CHECK(cv::norm(own.Raycast(view, cam).depth, open3d.Raycast(view, cam).depth, cv::NORM_INF) == 0.0);
}

TEST_CASE("TsdfOptions: integrator is p2i by default, open3d on request, anything else refused",
          "[unit]") {
  CHECK(TsdfOptions{}.integrator == "p2i");
  CHECK(TsdfOptions::FromYaml(YAML::Load("{integrator: open3d}"), "t.yaml").integrator == "open3d");
  CHECK_THROWS_WITH(TsdfOptions::FromYaml(YAML::Load("{integrator: fast}"), "t.yaml"),
                    Catch::Contains("integrator") && Catch::Contains("t.yaml"));
}

}  // namespace
}  // namespace p2i::fusion
