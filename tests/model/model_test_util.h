/// @file model_test_util.h
/// @brief Helpers shared by the model tests: Catch's CHECK restored after LibTorch's glog, temp
/// dirs, a tiny config, quiet trainer options, and exact comparison of module weights.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

#include <catch2/catch.hpp>
#include <torch/torch.h>

// LibTorch pulls in glog, whose CHECK(cond) replaces Catch's: a failing CHECK would abort the
// whole test binary, and passing ones are not counted. Every torch test includes this header
// after torch, so Catch's CHECK is restored here.
#undef CHECK
#define CHECK(...) \
  INTERNAL_CATCH_TEST("CHECK", Catch::ResultDisposition::ContinueOnFailure, __VA_ARGS__)

#include "model/p2i_config.h"
#include "model/trainer.h"

namespace p2i::model::testing {

/// An empty folder under the temp dir, unique per test process.
inline std::string TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("p2i_model_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

/// A model small enough to train a few steps in about a second at 32x32.
inline P2iConfig TinyConfig(const std::string& model = "p2i_net") {
  P2iConfig c;
  c.name = model == "p2i_net" ? "tiny" : "tiny_" + model;
  c.model = model;
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
  c.checkpoint_every = 3;
  c.Validate();
  return c;
}

/// One thread, no progress bar, `steps` in `phase` (0 = both, 1, 2).
inline TrainerOptions Quiet(const std::string& dir, int steps, int phase = 1,
                            bool resume = false) {
  TrainerOptions o;
  o.out_dir = dir;
  o.steps = steps;
  o.phase = phase;
  o.threads = 1;
  o.progress = false;
  o.max_val_frames = 4;
  o.resume = resume;
  return o;
}

/// Bit-identical parameters and buffers.
inline bool SameParameters(torch::nn::Module& a, torch::nn::Module& b) {
  auto pa = a.named_parameters(), pb = b.named_parameters();
  if (pa.size() != pb.size()) return false;
  for (const auto& kv : pa)
    if (!torch::equal(kv.value(), pb[kv.key()])) return false;
  auto ba = a.named_buffers(), bb = b.named_buffers();
  for (const auto& kv : ba)
    if (!torch::equal(kv.value(), bb[kv.key()])) return false;
  return true;
}

}  // namespace p2i::model::testing
