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
