/// @file fusion_method_test.cc
/// @brief The `fusion` registry entry with its learned refinement: the refine options are checked
/// at configure time (unknown keys, bad values, a missing net file, paths relative to the config
/// file), the shipped net is loaded and changes the views, and finetune_steps fine-tunes on the
/// method's own leave-one-out frames with the method's own blend k.
#include "refine/fusion_method.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>

#include <cstdlib>
#include <fstream>
#include <memory>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "model/learned_refiner.h"
#include "model/method_registry.h"
#include "model/p2i_synthesizer.h"
#include "refine/sim_scenes.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"

using namespace p2i;

namespace {

const std::string kShippedNet = std::string(P2I_SOURCE_DIR) + "/models/refine_sim.pt";

std::shared_ptr<scene::RgbdDataset> Sweep(int every, int count, int w, int h, int offset = 0) {
  const scene::SimScene sim = refine::MakeSimVariant("small_office", 1, 3);
  auto d = std::make_shared<scene::RgbdDataset>();
  d->camera = scene::SimScene::DefaultCamera(w, h);
  const auto poses = scene::GenerateArmSweep({});
  for (size_t i = offset; i < poses.size() && static_cast<int>(d->frames.size()) < count; i += every)
    d->frames.push_back(sim.Render(poses[i].pose, d->camera, poses[i].stamp));
  return d;
}

model::MethodFactory Configure(const std::string& yaml, const std::string& source = "bench.yaml") {
  return model::GetMethod("fusion").configure(YAML::Load(yaml), source);
}

double MeanAbsDiff(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_L1) / a.total(); }

/// A temporary folder, removed with its files.
struct TempDir {
  std::string path;
  TempDir() {
    char tmpl[] = "/tmp/p2i_fusion_method_XXXXXX";
    path = ::mkdtemp(tmpl);
  }
  ~TempDir() { (void)!std::system(("rm -rf '" + path + "'").c_str()); }
};

}  // namespace

TEST_CASE("fusion refine options: bad keys, values and a missing net name the key and the file", "[unit]") {
  const model::MethodInfo& info = model::GetMethod("fusion");
  CHECK(std::find(info.option_keys.begin(), info.option_keys.end(), "refine") != info.option_keys.end());
  CHECK_THROWS_WITH(Configure("{refine: {steps: 3}}"),
                    Catch::Contains("bench.yaml:1") && Catch::Contains("'steps'") &&
                        Catch::Contains("finetune_steps"));
  CHECK_THROWS_WITH(Configure("{refine: {finetune_steps: -1}}"),
                    Catch::Contains("bench.yaml") && Catch::Contains("finetune_steps must be >= 0"));
  CHECK_THROWS_WITH(Configure("{refine: {finetune_steps: 2.5}}"),
                    Catch::Contains("refine.finetune_steps must be an integer"));
  CHECK_THROWS_WITH(Configure("{refine: {folds: 1}}"), Catch::Contains("folds must be >= 2"));
  CHECK_THROWS_WITH(Configure("{refine: {net: /nonexistent/refine.pt}}"),
                    Catch::Contains("bench.yaml:1") && Catch::Contains("/nonexistent/refine.pt") &&
                        Catch::Contains("refine.net"));
  // Unknown top-level keys list 'refine' among the allowed ones.
  CHECK_THROWS_WITH(Configure("{refin: {}}"), Catch::Contains("'refin'") && Catch::Contains("refine"));
  // The defaults: no refinement.
  const refine::FusionRefineOptions none = refine::FusionRefineOptions::FromYaml(YAML::Load("{}"), "x");
  CHECK_FALSE(none.Enabled());
}

TEST_CASE("fusion refine.net is relative to the config file it is written in", "[unit]") {
  TempDir dir;
  ::mkdir((dir.path + "/configs").c_str(), 0700);
  ::mkdir((dir.path + "/models").c_str(), 0700);
  {
    std::ifstream in(kShippedNet, std::ios::binary);
    REQUIRE(in.good());
    std::ofstream out(dir.path + "/models/net.pt", std::ios::binary);
    out << in.rdbuf();
  }
  const std::string config = dir.path + "/configs/bench.yaml";
  std::ofstream(config) << "# a config\n";
  const refine::FusionRefineOptions o =
      refine::FusionRefineOptions::FromYaml(YAML::Load("{net: ../models/net.pt}"), config);
  CHECK(o.net == dir.path + "/configs/../models/net.pt");
  CHECK(o.Enabled());
  // From a source that is not a file (a node parameter), the path is taken as given.
  CHECK_THROWS_WITH(refine::FusionRefineOptions::FromYaml(YAML::Load("{net: ../models/net.pt}"),
                                                          "synthesizer parameter method_options"),
                    Catch::Contains("no refinement file '../models/net.pt'"));
}

TEST_CASE("fusion with refine.net loads the shipped refinement and refines the views", "[unit]") {
  model::MethodInputs in;
  in.training = Sweep(6, 16, 64, 48);
  const scene::Pose at = scene::GenerateArmSweep({})[9].pose;  // between two training frames
  auto plain = Configure("{tsdf: {voxel_size_m: 0.04}}")(in);
  auto refined = Configure("{tsdf: {voxel_size_m: 0.04}, refine: {net: " + kShippedNet + "}}")(in);
  CHECK(plain->ParameterCount() == 0);
  CHECK(refined->ParameterCount() == model::LearnedRefiner::Load(kShippedNet, 4)->ParameterCount());
  CHECK(refined->ParameterCount() > 0);
  const scene::RgbdSample a = plain->Render(at);
  const scene::RgbdSample b = refined->Render(at);
  REQUIRE(b.rgb.size() == a.rgb.size());
  REQUIRE(b.depth.size() == a.depth.size());
  CHECK(MeanAbsDiff(a.rgb, b.rgb) > 0.05);  // the net changes the blend ...
  CHECK(MeanAbsDiff(a.rgb, b.rgb) < 60.0);  // ... and does not replace it with noise
  CHECK(cv::countNonZero(b.depth > 0.0f) > 0.9 * b.depth.total());
  // The shipped net is for k = 4: another blend k is refused, naming the layout.
  CHECK_THROWS_WITH(Configure("{blend: {k: 2}, refine: {net: " + kShippedNet + "}}")(in),
                    Catch::Contains("k2") || Catch::Contains("layout"));
}

TEST_CASE("fusion p2i_fill: P2I-NET's view fills the pixels the TSDF never observed", "[unit]") {
  const std::string ckpt = std::string(P2I_SOURCE_DIR) + "/models/demo_small_office_64.pt";
  const scene::CameraInfo camera = model::LoadSynthesizer(ckpt)->Camera();  // 64x64, f = 70
  const scene::SimScene sim = scene::SimScene::BuiltIn("small_office");
  const auto poses = scene::GenerateArmSweep({});
  model::MethodInputs in;
  auto d = std::make_shared<scene::RgbdDataset>();
  d->camera = camera;
  for (size_t i = 0; i < 3; ++i) d->frames.push_back(sim.Render(poses[i * 6].pose, camera, poses[i * 6].stamp));
  in.training = d;
  // The far field off: every pixel without a fused surface is the filler's (with it on, those
  // whose keyframes saw nothing in range keep its colour: tests/fusion).
  auto plain = Configure("{fill_holes: false, blend: {far_depth_m: 0}}")(in);
  auto filled = Configure("{fill_holes: false, blend: {far_depth_m: 0}, p2i_fill: " + ckpt + "}")(in);
  // The first later pose whose view the three fused frames cover only in part.
  scene::Pose far;
  scene::RgbdSample a;
  for (size_t i = 13; i < poses.size(); i += 2) {
    far = poses[i].pose;
    a = plain->Render(far);
    const double holes = cv::countNonZero(a.depth <= 0.0f) / static_cast<double>(a.depth.total());
    if (holes > 0.2 && holes < 0.8) break;
  }
  const scene::RgbdSample b = filled->Render(far);
  const scene::RgbdSample g = model::LoadSynthesizer(ckpt)->Render(far);
  const cv::Mat hole = a.depth <= 0.0f;
  REQUIRE(cv::countNonZero(hole) > static_cast<int>(a.depth.total() / 10));
  REQUIRE(cv::countNonZero(hole) < static_cast<int>(a.depth.total()));
  cv::Mat diff_hole, diff_seen;
  cv::absdiff(b.rgb, g.rgb, diff_hole);
  cv::absdiff(b.rgb, a.rgb, diff_seen);
  CHECK(cv::norm(diff_hole, cv::NORM_L1, hole) == 0.0);    // holes: G's pixels
  CHECK(cv::norm(diff_seen, cv::NORM_L1, ~hole) == 0.0);   // observed: the blend's
  CHECK(cv::norm(b.rgb, a.rgb, cv::NORM_L1) > 0.0);
  // Bad paths and a filler at another camera are errors that name the key.
  CHECK_THROWS_WITH(Configure("{p2i_fill: /nonexistent/g.pt}", "bench.yaml"),
                    Catch::Contains("p2i_fill") && Catch::Contains("/nonexistent/g.pt"));
  model::MethodInputs other;
  other.training = Sweep(6, 3, 48, 48);
  auto mismatched = Configure("{p2i_fill: " + ckpt + "}")(other);
  CHECK_THROWS_WITH(mismatched->Render(far), Catch::Contains("hole filler") && Catch::Contains("48x48"));
}

TEST_CASE("fusion with refine.finetune_steps fine-tunes a fresh net on its own leave-one-out frames", "[unit]") {
  model::MethodInputs in;
  in.training = Sweep(6, 16, 48, 36);
  in.threads = 1;
  const scene::Pose at = scene::GenerateArmSweep({})[9].pose;
  // k = 2: the samples must be rendered with the method's own blend (a k = 4 layout would be
  // refused by the k = 2 net).
  const std::string base = "{tsdf: {voxel_size_m: 0.04}, blend: {k: 2}";
  auto plain = Configure(base + "}")(in);
  auto untuned = Configure(base + ", refine: {finetune_steps: 0, net: ''}}")(in);
  CHECK(untuned->ParameterCount() == 0);  // no net, no steps: no refinement at all
  auto tuned = Configure(base + ", refine: {finetune_steps: 15, batch_size: 2, lr: 0.003}}")(in);
  CHECK(tuned->ParameterCount() > 0);
  const scene::RgbdSample a = plain->Render(at);
  const scene::RgbdSample b = tuned->Render(at);
  // A fresh net is the identity on the blend; fifteen steps move it off.
  CHECK(MeanAbsDiff(a.rgb, b.rgb) > 0.05);
  // Too few overlapping frames: a clear error instead of a silent untrained net.
  model::MethodInputs one;
  one.training = Sweep(6, 1, 48, 36);
  CHECK_THROWS_WITH(Configure(base + ", refine: {finetune_steps: 5}}")(one),
                    Catch::Contains("refine.finetune_steps") && Catch::Contains("overlapping"));
}
