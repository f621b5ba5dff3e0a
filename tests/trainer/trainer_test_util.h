/// @file trainer_test_util.h
/// @brief Shared helpers of the trainer tests: temp folders, a tiny config, sim frames.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include "model/p2i_config.h"
#include "scene/rgbd_sample.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"
#include "tests/temp_dir.h"
#include "tests/tiny_config.h"

namespace p2i::trainer::testing {

/// p2i::testing::FreshDir under the trainer tests' prefix (kept after the test for inspection).
inline std::string TempDir(const std::string& name) {
  return p2i::testing::FreshDir("trainer_test_" + name);
}

/// tests/tiny_config.h's model, checkpointed every 5 steps.
inline model::P2iConfig TinyConfig() {
  model::P2iConfig c = p2i::testing::TinyConfig();
  c.checkpoint_every = 5;
  return c;
}

/// `n` frames of the built-in small_office seen along an arm sweep, at 48x36 (not square, so
/// the buffer's centre crop is exercised).
inline scene::RgbdDataset SimFrames(size_t n) {
  const scene::SimScene sim = scene::SimScene::BuiltIn("small_office");
  scene::RgbdDataset d;
  d.camera = scene::CameraInfo::Pinhole(48, 36, 40.0, 40.0, 24.0, 18.0, "sim");
  const auto poses = scene::GenerateArmSweep(scene::ArmSweepOptions());
  const size_t stride = std::max<size_t>(1, poses.size() / n);
  for (size_t i = 0; i < n && i * stride < poses.size(); ++i) {
    const auto& p = poses[i * stride];
    d.frames.push_back(sim.Render(p.pose, d.camera, p.stamp));
  }
  return d;
}

}  // namespace p2i::trainer::testing
