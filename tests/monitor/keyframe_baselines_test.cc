/// @file keyframe_baselines_test.cc
/// @brief The monitor's free baselines: exact at a keyframe's pose, sensible between keyframes,
/// none before the first keyframe.
#include <catch2/catch.hpp>

#include "nodes/monitor/keyframe_baselines.h"
#include "scene/image_ops.h"
#include "scene/trajectory.h"

using namespace p2i;

namespace {

scene::RgbdSample Truth(const scene::SimScene& sim, const scene::CameraInfo& cam,
                        const scene::Pose& pose, int size) {
  return scene::CenterCropResizeSample(sim.Render(pose, cam), size, size);
}

}  // namespace

TEST_CASE("KeyframeBaselines: nearest keyframe and depth warp on the view's pose", "[unit]") {
  const scene::SimScene sim = scene::SimScene::BuiltIn("small_office");
  const scene::CameraInfo cam = scene::SimScene::DefaultCamera(160, 120);
  const auto poses = scene::GenerateArmSweep(scene::ArmSweepOptions());
  REQUIRE(poses.size() > 40);
  nodes::KeyframeBaselines b(&sim, cam);
  const scene::Pose query = poses[20].pose;
  CHECK_FALSE(b.Score(query, Truth(sim, cam, query, 32)).has_value());  // no keyframe yet

  for (size_t i = 0; i < 40; i += 4) b.AddKeyframe(poses[i].pose);
  CHECK(b.Size() == 10);
  // At a keyframe's own pose both reproduce it (nearest exactly: PSNR at the cap).
  const auto at = b.Score(query, Truth(sim, cam, query, 32));
  REQUIRE(at.has_value());
  CHECK(at->nearest_psnr > 60.0);
  CHECK(at->nearest_ssim == Approx(1.0).margin(1e-6));
  CHECK(at->warp_psnr > 25.0);
  // Between keyframes: finite, below the exact copy; the warp of the 4 nearest moves the
  // pixels with the pose, so it is no worse than the nearest frame here.
  const scene::Pose between = poses[22].pose;
  const auto mid = b.Score(between, Truth(sim, cam, between, 32));
  REQUIRE(mid.has_value());
  CHECK(mid->nearest_psnr > 10.0);
  CHECK(mid->nearest_psnr < 60.0);
  CHECK(mid->warp_psnr > mid->nearest_psnr - 0.5);
  CHECK(mid->warp_ssim > 0.0);
  // Another view size re-renders the keyframes at that size.
  const auto big = b.Score(between, Truth(sim, cam, between, 48));
  REQUIRE(big.has_value());
  CHECK(big->nearest_psnr > 10.0);
}
