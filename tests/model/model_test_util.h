/// @file model_test_util.h
/// @brief Helpers shared by the model tests: Catch's CHECK restored after LibTorch's glog, temp
/// dirs and the tiny config (tests/temp_dir.h, tests/tiny_config.h), quiet trainer options, and
/// exact comparison of module weights.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include <catch2/catch.hpp>
#include <torch/torch.h>

// LibTorch pulls in glog, whose CHECK(cond) replaces Catch's: a failing CHECK would abort the
// whole test binary, and passing ones are not counted. Every torch test includes this header
// after torch, so Catch's CHECK is restored here.
#undef CHECK
#define CHECK(...) \
  INTERNAL_CATCH_TEST("CHECK", Catch::ResultDisposition::ContinueOnFailure, __VA_ARGS__)

#include "model/densify.h"
#include "model/p2i_config.h"
#include "model/export.h"
#include "model/procedural_dataset.h"
#include "model/trainer.h"
#include "tests/read_file.h"
#include "tests/temp_dir.h"
#include "tests/tiny_config.h"

namespace p2i::model::testing {

/// p2i::testing::FreshDir under the model tests' prefix (kept after the test for inspection).
inline std::string TempDir(const std::string& name) {
  return p2i::testing::FreshDir("model_test_" + name);
}

using p2i::testing::TinyConfig;

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

/// `captured` frames on a line along x, 1 cm apart, facing one way, with `per_gap` densified
/// views (model/densify.h ids) evenly between each pair of neighbours. Per-axis normalisation
/// puts the captured frames 2 / ((captured - 1) 1.1) apart in the pose input (5 % margin).
inline p2i::scene::RgbdDataset FramesOnALine(int captured, int per_gap) {
  const int n = captured + (captured - 1) * per_gap;
  auto data = MakeProceduralDataset(n, 32);
  const double step = 0.01 / (per_gap + 1);
  for (int i = 0; i < n; ++i) {
    auto& f = data.frames[static_cast<size_t>(i)];
    f.pose = p2i::scene::Pose(Eigen::Vector3d(step * i, 0, 0), Eigen::Quaterniond::Identity());
    if (i % (per_gap + 1) != 0) f.id = std::string(kDensifiedIdPrefix) + std::to_string(i);
  }
  return data;
}

/// The first line of a train log (`train_log*.jsonl`): its start event.
inline nlohmann::json StartEvent(const std::string& log_path) {
  const std::string text = p2i::testing::ReadFile(log_path);
  return nlohmann::json::parse(text.substr(0, text.find('\n')));
}

/// `c` with the Fourier pose encoding and `fourier_bands: auto`.
inline P2iConfig AutoFourierBandsConfig(P2iConfig c) {
  c.pose_encoding = "fourier";
  c.fourier_bands = kAutoFourierBands;
  c.Validate();
  return c;
}

}  // namespace p2i::model::testing
