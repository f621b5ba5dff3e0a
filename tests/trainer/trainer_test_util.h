/// @file trainer_test_util.h
/// @brief Shared helpers of the trainer tests: temp folders, a tiny config, sim frames.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "model/p2i_config.h"
#include "scene/rgbd_sample.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"

namespace p2i::trainer::testing {

inline std::string TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("p2i_trainer_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

/// A 32x32 P2I-NET small enough to train a few steps per second on one core.
inline model::P2iConfig TinyConfig() {
  model::P2iConfig c;
  c.name = "tiny";
  c.resolution = 32;
  c.g_schedule = "custom";
  c.g_widths = {16, 16, 8, 8};
  c.g_fc_width = 16;
  c.d_base_width = 8;
  c.d_max_width = 16;
  c.latent_dim = 32;
  c.mapping_width = 16;
  c.enet_width = 8;
  c.enet_blocks = 1;
  c.batch_size = 4;
  c.val_every = 5;
  c.checkpoint_every = 5;
  c.Validate();
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
