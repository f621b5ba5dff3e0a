/// @file sim_ceiling_test.cc
/// @brief The bench's ceiling rows (eval/sim_ceiling.h): the sim's own render at the test poses,
/// scored like a method. The config refuses them without a sim scene; the rows land in
/// results.csv; with the sensor model off the exact render reproduces the test frames, with it on
/// the frame's exposure and white balance explain part of what separates them.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "eval/bench_config.h"
#include "eval/bench_runner.h"
#include "eval/sim_ceiling.h"
#include "model/metrics.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"

namespace fs = std::filesystem;

namespace {

std::string ConfigError(const std::string& text) {
  try {
    p2i::eval::BenchConfig::FromYamlString(text, "ceiling.yaml");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

/// method -> PSNR of the rows of results.csv.
std::map<std::string, double> PsnrByMethod(const std::string& csv_path) {
  std::ifstream in(csv_path);
  std::string line;
  std::getline(in, line);  // header: method,method_type,setting,size,resolution,seed,train_frames,test_views,psnr_db,...
  std::map<std::string, double> out;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (f.size() > 8) out[f[0]] = std::stod(f[8]);
  }
  return out;
}

}  // namespace

TEST_CASE("Bench ceiling: the config takes the kinds on a sim scene only", "[unit]") {
  const std::string sim = "dataset: {scene: builtin:small_office}\nsettings: [a1]\nmethods: [nearest]\nsizes: [64]\n";
  const auto c =
      p2i::eval::BenchConfig::FromYamlString(sim + "ceiling: [exact, auto_exposure, colour]\n", "ceiling.yaml");
  CHECK(c.ceiling == std::vector<std::string>{"exact", "auto_exposure", "colour"});
  CHECK(p2i::eval::BenchConfig::FromYamlString(sim, "ceiling.yaml").ceiling.empty());
  std::string e = ConfigError(sim + "ceiling: [exact, shiny]\n");
  CHECK(e.find("shiny") != std::string::npos);
  CHECK(e.find("ceiling.yaml:5") != std::string::npos);
  CHECK(ConfigError(sim + "ceiling: [exact, exact]\n").find("repeats") != std::string::npos);
  CHECK(ConfigError(sim + "ceiling: exact\n").find("list") != std::string::npos);
  e = ConfigError("dataset: {path: /nowhere}\nsettings: [a1]\nmethods: [nearest]\nsizes: [64]\nceiling: [exact]\n");
  CHECK(e.find("needs a sim scene") != std::string::npos);
  CHECK(e.find("ceiling.yaml:5") != std::string::npos);
}

TEST_CASE("Bench ceiling: the sensor options of each kind", "[unit]") {
  auto s = p2i::scene::SimSensorOptions::Realistic(7);
  s.pixel_samples = 3;
  const auto exact = p2i::eval::CeilingSensor(s, "exact");
  CHECK(exact.pixel_samples == 3);
  CHECK_FALSE(exact.AnyNoise());
  CHECK_FALSE(exact.AnyColour());
  CHECK_FALSE(exact.MotionBlur());
  const auto auto_exposure = p2i::eval::CeilingSensor(s, "auto_exposure");
  CHECK(auto_exposure.auto_exposure == s.auto_exposure);
  CHECK(auto_exposure.exposure_drift == 0.0);
  CHECK(auto_exposure.white_balance_drift == 0.0);
  CHECK_FALSE(auto_exposure.AnyNoise());
  const auto colour = p2i::eval::CeilingSensor(s, "colour");
  CHECK(colour.AnyColour());
  CHECK(colour.exposure_drift == s.exposure_drift);
  CHECK(colour.white_balance_drift == s.white_balance_drift);
  CHECK(colour.auto_exposure == s.auto_exposure);
  CHECK_FALSE(colour.AnyNoise());
  CHECK_FALSE(colour.MotionBlur());
  CHECK_THROWS_AS(p2i::eval::CeilingSensor(s, "shiny"), std::invalid_argument);
}

TEST_CASE("Bench ceiling: the view at a test pose renders at that frame's stamp", "[unit]") {
  // The colour ceiling reproduces a still frame with drift but no noise or blur exactly only at
  // the frame's own stamp: at stamp 0 the drifted gains differ.
  auto sim = p2i::scene::SimScene::FromSpec("builtin:small_office");
  p2i::scene::SimSensorOptions drift;
  drift.exposure_drift = 0.2;
  drift.white_balance_drift = 0.1;
  drift.drift_period_s = 2.0;
  sim.set_sensor_options(drift);
  const auto camera = p2i::scene::SimScene::DefaultCamera(48, 48);
  p2i::scene::AdjacentSweepsOptions sweeps;
  sweeps.count = 1;
  const auto trajectory = p2i::scene::GenerateAdjacentSweeps(sweeps).front();
  p2i::scene::RgbdDataset test;
  test.camera = camera;
  test.frames.push_back(sim.RenderOnTrajectory(trajectory, 13, camera));
  REQUIRE(test.frames[0].stamp > 0.5);
  p2i::eval::SimCeilingView colour(sim, "colour", camera, 48, 48, test);
  p2i::eval::SimCeilingView exact(sim, "exact", camera, 48, 48, test);
  CHECK(colour.Name() == "ceiling_colour");
  CHECK(colour.Camera().image_width == 48);
  const auto v = colour.Render(test.frames[0].pose);
  REQUIRE(v.rgb.size() == test.frames[0].rgb.size());
  const double same_stamp = p2i::model::Psnr(v.rgb, test.frames[0].rgb);
  const double without_drift = p2i::model::Psnr(exact.Render(test.frames[0].pose).rgb, test.frames[0].rgb);
  CHECK(same_stamp > 60.0);
  CHECK(without_drift < 40.0);
  // Another pose (not a test frame's) renders at stamp 0, where the gains are others.
  p2i::scene::RgbdDataset other = test;
  other.frames[0].stamp = 0.0;
  p2i::eval::SimCeilingView at_zero(sim, "colour", camera, 48, 48, other);
  CHECK(p2i::model::Psnr(at_zero.Render(test.frames[0].pose).rgb, test.frames[0].rgb) < same_stamp - 10.0);
}

TEST_CASE("Bench ceiling: p2i bench writes the ceiling rows beside the methods", "[unit]") {
  const fs::path dir = fs::temp_directory_path() / ("p2i_bench_ceiling_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  auto run = [&](const std::string& sensor, const std::string& name) {
    const std::string config = (dir / (name + ".yaml")).string();
    std::ofstream(config) << "dataset: {scene: builtin:small_office, trajectories: 1, frame_step: 12,"
                             " max_frames: 16, sensor: " << sensor << "}\n"
                             "settings: [a1]\n"
                             "period: 8\n"
                             "max_test_views: 2\n"
                             "methods: [nearest]\n"
                             "sizes: [{name: r32, resolution: 32}]\n"
                             "threads: 1\n"
                             "strip_views: 0\n"
                             "stability: {enabled: false}\n"
                             "ceiling: [exact, colour]\n";
    p2i::eval::BenchOptions o;
    o.config_path = config;
    o.out_dir = (dir / name).string();
    o.quiet = true;
    p2i::eval::RunBench(o);
    return PsnrByMethod((dir / name / "results.csv").string());
  };
  const auto realistic = run("{preset: realistic, seed: 1}", "realistic");
  REQUIRE(realistic.count("nearest") == 1);
  REQUIRE(realistic.count("ceiling_exact") == 1);
  REQUIRE(realistic.count("ceiling_colour") == 1);
  // The scene itself beats a neighbouring frame; the frame's own gains explain part of the rest.
  CHECK(realistic.at("ceiling_exact") > realistic.at("nearest") + 3.0);
  CHECK(realistic.at("ceiling_colour") > realistic.at("ceiling_exact") + 0.5);
  CHECK(realistic.at("ceiling_colour") < 60.0);  // noise and blur stay
  // Without the sensor model the exact render is the test frame (poses through the capture's
  // text file move a few edge pixels at most).
  const auto none = run("{preset: none}", "none");
  CHECK(none.at("ceiling_exact") > 45.0);
  std::ifstream report(dir / "none" / "report.md");
  std::stringstream text;
  text << report.rdbuf();
  CHECK(text.str().find("ceiling_exact") != std::string::npos);
  fs::remove_all(dir);
}
