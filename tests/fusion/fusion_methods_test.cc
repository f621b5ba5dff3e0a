/// @file fusion_methods_test.cc
/// @brief `fusion` and `open3d_tsdf` through the method registry: options checked at configure
/// time, factories build working synthesizers over the training frames.
#include "fusion/fusion_methods.h"

#include <memory>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "model/method_registry.h"
#include "tests/fusion/fusion_test_util.h"

namespace p2i::fusion {
namespace {

using testing::At;
using testing::Cam;
using testing::PlaneScene;

TEST_CASE("registry: fusion and open3d_tsdf are listed, check options and build from frames", "[unit]") {
  const PlaneScene plane;
  auto training = std::make_shared<scene::RgbdDataset>();
  training->camera = Cam(32, 24, 30.0);
  for (int i = 0; i < 3; ++i)
    training->frames.push_back(plane.Render(At(0.05 * i, 0.0, 0.0), training->camera));
  model::MethodInputs in;
  in.training = training;

  for (const char* name : {"fusion", "open3d_tsdf"}) {
    INFO(name);
    const model::MethodInfo& info = model::GetMethod(name);
    CHECK_FALSE(info.learned);
    CHECK(model::MethodNames().find(name) != std::string::npos);
    auto synth = info.configure(YAML::Load("{tsdf: {voxel_size_m: 0.02}, fill_holes: true}"),
                                "bench.yaml")(in);
    const scene::RgbdSample v = synth->Render(At(0.025, 0.0, 0.0));
    REQUIRE(v.rgb.size() == cv::Size(32, 24));
    CHECK(cv::countNonZero(v.depth > 0.0f) > 0.9 * 32 * 24);
    CHECK_THROWS_WITH(info.configure(YAML::Load("{tsdf: {voxel: 0.02}}"), "bench.yaml"),
                      Catch::Contains("bench.yaml") && Catch::Contains("voxel"));
    CHECK_THROWS_WITH(info.configure(YAML::Load("{k: 4}"), "bench.yaml"), Catch::Contains("'k'"));
    CHECK_THROWS_WITH(info.configure(YAML::Node(), "t")(model::MethodInputs{}),
                      Catch::Contains("training frames"));
  }
}

}  // namespace
}  // namespace p2i::fusion
