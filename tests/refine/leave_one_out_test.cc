/// @file leave_one_out_test.cc
/// @brief Leave-one-out samples on a tiny sim scene: every frame gets a sample rendered without
/// itself, and fitting lowers the loss.
#include <catch2/catch.hpp>

#include "model/learned_refiner.h"
#include "refine/leave_one_out.h"
#include "refine/sim_scenes.h"
#include "scene/image_ops.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"
#include "tests/fusion/fusion_test_util.h"

using namespace p2i;

namespace {

scene::RgbdDataset Sweep(int every, int count, int w, int h, int offset = 0) {
  const scene::SimScene sim = refine::MakeSimVariant("small_office", 1, 3);
  scene::RgbdDataset d;
  d.camera = scene::SimScene::DefaultCamera(w, h);
  const auto poses = scene::GenerateArmSweep({});
  for (size_t i = offset; i < poses.size() && static_cast<int>(d.frames.size()) < count; i += every)
    d.frames.push_back(sim.Render(poses[i].pose, d.camera, poses[i].stamp));
  return d;
}

}  // namespace

TEST_CASE("Leave-one-out samples of a tiny scene lower the refinement loss when fitted", "[unit]") {
  const scene::RgbdDataset d = Sweep(10, 12, 48, 36);
  refine::LeaveOneOutOptions o;
  o.folds = 3;
  o.scene.voxel_size_m = 0.05;
  const auto samples = refine::MakeLeaveOneOutSamples(d, d.camera, o);
  REQUIRE(samples.size() >= 8);  // a few edge frames see nothing the others fused
  CHECK(samples[0].input.channels == fusion::RefinementChannels(o.scene.k));
  CHECK(samples[0].target_rgb.cols == 48);
  // Rendered without itself: the blend is not the frame (else the task would be trivial).
  cv::Mat blend8;
  samples[0].input.base_rgb.convertTo(blend8, CV_8UC3, 255.0);
  CHECK(cv::norm(blend8, samples[0].target_rgb, cv::NORM_L1) > 0);
  auto r = model::LearnedRefiner::Fresh(o.scene.k, [] {
    model::RefineNetOptions n;
    n.widths = {8, 16};
    return n;
  }());
  model::RefineTrainOptions t;
  t.steps = 60;
  t.batch_size = 2;
  t.lr = 2e-3;
  const model::RefineFitReport fit = r->refiner().Fit(samples, t);
  INFO("loss " << fit.first_loss << " -> " << fit.last_loss);
  CHECK(fit.last_loss < fit.first_loss);
}

TEST_CASE("Leave-one-out folds render with the auto choices a served scene of their frames makes", "[unit]") {
  // Each frame's depth is scaled by 1 + 0.2 x (its camera's x): neighbours share the bias, the
  // TSDF averages it away, so `depth: auto` picks the keyframes' depth. The refinement must train
  // on the candidates it will be served: a fold prepared like a served scene, not the raycast an
  // unprepared scene renders.
  fusion::testing::PlaneScene plane;
  plane.patch_z = 1.5;
  const scene::CameraInfo cam = fusion::testing::Cam(48, 36, 45);
  scene::RgbdDataset d;
  d.camera = cam;
  for (int i = 0; i < 9; ++i) {
    const double x = -0.16 + 0.04 * i;
    scene::RgbdSample f = plane.Render(fusion::testing::At(x, 0, 0), cam);
    f.depth = f.depth * (1.0 + 0.2 * x);
    f.id = "f" + std::to_string(i);
    d.frames.push_back(f);
  }
  fusion::FusionSceneOptions o;
  o.blend.depth = "auto";
  o.blend.align = fusion::SlotAlignmentOptions{};  // off: this test is about the depth choice
  refine::LeaveOneOutOptions loo;
  loo.folds = 3;
  loo.fusion_scene = o;
  const auto samples = refine::MakeLeaveOneOutSamples(d, cam, loo);
  REQUIRE(samples.size() == 9);

  // Fold 0 (frames 0, 3, 6 held out) built as a served scene: its first sample is frame 0's view.
  fusion::FusionScene served(cam, o);
  for (size_t i = 0; i < d.frames.size(); ++i)
    if (i % 3 != 0) served.AddFrame(d.frames[i]);
  served.Prepare();
  REQUIRE(served.keyframe_depth());
  const model::RefineSample want =
      model::MakeRefineSample(served.RenderCandidates(d.frames[0].pose, cam), d.frames[0]);
  CHECK(cv::norm(samples[0].input.base_depth, want.input.base_depth, cv::NORM_INF) == 0.0);
  CHECK(cv::norm(samples[0].input.base_rgb, want.input.base_rgb, cv::NORM_INF) == 0.0);
  fusion::CandidateRequest raycast;
  raycast.keyframe_depth = false;
  const cv::Mat raycast_depth = served.RenderCandidates(d.frames[0].pose, cam, raycast).depth;
  CHECK(cv::norm(samples[0].input.base_depth, raycast_depth, cv::NORM_INF) > 0.01);
}
