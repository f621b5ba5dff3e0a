/// @file method_registry_test.cc
/// @brief The method registry: names and aliases, learned flags, options checked at configure
/// time, factories that build working synthesizers.
#include "model/method_registry.h"

#include <set>
#include <stdexcept>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "scene/sim_scene.h"
#include "scene/trajectory.h"

namespace p2i::model {
namespace {

std::shared_ptr<const scene::RgbdDataset> SmallTraining() {
  const scene::SimScene sim = scene::SimScene::BuiltIn("small_office");
  auto data = std::make_shared<scene::RgbdDataset>();
  data->camera = scene::SimScene::DefaultCamera(24, 18);
  const auto sweep = scene::GenerateArmSweep({});
  for (size_t i = 0; i < sweep.size(); i += 60) {
    data->frames.push_back(sim.Render(sweep[i].pose, data->camera));
  }
  return data;
}

TEST_CASE("The registry lists each method once, with unique names and aliases", "[unit]") {
  std::set<std::string> seen;
  for (const MethodInfo& m : Methods()) {
    CHECK(seen.insert(m.name).second);
    for (const auto& a : m.aliases) CHECK(seen.insert(a).second);
    CHECK_FALSE(m.summary.empty());
    CHECK(m.configure);
    if (m.learned) {
      CHECK_FALSE(m.default_preset.empty());
      CHECK_FALSE(m.trainer_model.empty());
    }
    CHECK(&GetMethod(m.name) == &m);
  }
  for (const char* name : {"p2i", "cnn", "nearest", "warp"}) CHECK(FindMethod(name) != nullptr);
  CHECK(FindMethod("p2i_net") == FindMethod("p2i"));
  CHECK(FindMethod("cnn_baseline")->name == "cnn");
  CHECK(GetMethod("p2i").learned);
  CHECK_FALSE(GetMethod("warp").learned);
  CHECK(FindMethod("nerf") == nullptr);
  CHECK_THROWS_WITH(GetMethod("nerf"), Catch::Contains("nerf") && Catch::Contains(MethodNames()));
  CHECK(MethodNames().rfind("p2i, cnn, nearest, warp", 0) == 0);
}

TEST_CASE("Configure checks options at start-up, factories build from frames", "[unit]") {
  const auto training = SmallTraining();
  MethodInputs in;
  in.training = training;

  auto nearest = GetMethod("nearest").configure(YAML::Node(), "test")(in);
  const scene::RgbdSample n = nearest->Render(training->frames[2].pose);
  CHECK(cv::norm(n.rgb, training->frames[2].rgb, cv::NORM_L1) == 0.0);

  auto warp = GetMethod("warp").configure(YAML::Load("{k: 2}"), "test")(in);
  const scene::RgbdSample w = warp->Render(training->frames[2].pose);
  CHECK(w.rgb.size() == cv::Size(24, 18));

  CHECK_THROWS_WITH(GetMethod("warp").configure(YAML::Load("{kk: 2}"), "bench.yaml"),
                    Catch::Contains("bench.yaml") && Catch::Contains("kk"));
  CHECK_THROWS_WITH(GetMethod("nearest").configure(YAML::Load("{k: 2}"), "bench.yaml"),
                    Catch::Contains("'k'"));
  CHECK_THROWS_AS(GetMethod("p2i").configure(YAML::Load("{k: 2}"), "bench.yaml"),
                  std::runtime_error);

  // Missing inputs are named when the synthesizer is built.
  CHECK_THROWS_WITH(GetMethod("warp").configure(YAML::Node(), "t")(MethodInputs{}),
                    Catch::Contains("training frames"));
  CHECK_THROWS_WITH(GetMethod("p2i").configure(YAML::Node(), "t")(MethodInputs{}),
                    Catch::Contains("checkpoint"));
  MethodInputs missing;
  missing.checkpoint_path = "/nonexistent/ckpt.pt";
  CHECK_THROWS(GetMethod("cnn").configure(YAML::Node(), "t")(missing));
}

}  // namespace
}  // namespace p2i::model
