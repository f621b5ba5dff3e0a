/// @file refine_tuner.cc
/// @brief RefineTuner: offered keyframes -> leave-one-out samples -> Adam steps -> the net file.
#include "nodes/trainer/refine_tuner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "model/learned_refiner.h"
#include "refine/leave_one_out.h"
#include "scene/image_ops.h"

namespace p2i::trainer {

namespace fs = std::filesystem;

void RefineTunerOptions::Validate() const {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("refine tuner: " + what);
  };
  scene.Validate();
  if (steps_per_round < 1) fail("steps_per_round must be >= 1, got " + std::to_string(steps_per_round));
  if (window_keyframes < 2)
    fail("window_keyframes must be >= 2, got " + std::to_string(window_keyframes));
  if (min_keyframes < 2) fail("min_keyframes must be >= 2, got " + std::to_string(min_keyframes));
  if (view_width < 16) fail("view_width must be >= 16, got " + std::to_string(view_width));
  if (folds < 2) fail("folds must be >= 2, got " + std::to_string(folds));
  if (out_dir.empty()) fail("out_dir is empty");
  if (!net.empty() && !fs::is_regular_file(net))
    fail("net: no file '" + net + "' (a `p2i refine train-sim` output such as "
         "models/refine_sim.pt, or '' for a fresh net)");
  model::RefineTrainOptions t = train;
  t.steps = steps_per_round;
  t.Validate();
}

RefineTuner::RefineTuner(RefineTunerOptions options) : options_(std::move(options)) {
  options_.Validate();
  const int k = options_.scene.blend.k;
  refiner_ = options_.net.empty() ? model::LearnedRefiner::Fresh(k)
                                  : model::LearnedRefiner::Load(options_.net, k);
  fs::create_directories(options_.out_dir);
  thread_ = std::thread([this] { Run(); });
}

RefineTuner::~RefineTuner() { Stop(); }

void RefineTuner::Offer(const std::vector<scene::RgbdSample>& keyframes,
                        const scene::CameraInfo& camera) {
  const size_t n = std::min(keyframes.size(), static_cast<size_t>(options_.window_keyframes));
  scene::RgbdDataset d;
  d.camera = camera;
  d.frames.assign(keyframes.end() - static_cast<std::ptrdiff_t>(n), keyframes.end());
  std::lock_guard<std::mutex> lock(mutex_);
  if (stopping_) return;
  pending_ = std::move(d);
  cv_.notify_all();
}

RefineTuner::Net RefineTuner::LatestNet() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

bool RefineTuner::WaitForRounds(uint64_t rounds, double timeout_s) const {
  std::unique_lock<std::mutex> lock(mutex_);
  return cv_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                      [&] { return stats_.rounds >= rounds; });
}

RefineTuner::Stats RefineTuner::GetStats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void RefineTuner::Stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

std::string RefineTuner::NetPath(uint64_t round) const {
  char name[40];
  std::snprintf(name, sizeof(name), "online_refine_%06llu.pt",
                static_cast<unsigned long long>(round));
  return (fs::path(options_.out_dir) / name).string();
}

void RefineTuner::Run() {
  for (;;) {
    scene::RgbdDataset frames;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [this] { return stopping_ || pending_.has_value(); });
      if (stopping_) return;
      frames = std::move(*pending_);
      pending_.reset();
    }
    try {
      Round(frames);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      stats_.last_error = e.what();
      ++stats_.offers_skipped;
    }
  }
}

void RefineTuner::Round(const scene::RgbdDataset& frames) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto skip = [this](const std::string& why) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.offers_skipped;
    stats_.last_error = why;
  };
  if (static_cast<int>(frames.frames.size()) < options_.min_keyframes) {
    skip(std::to_string(frames.frames.size()) + " keyframes, fewer than min_keyframes " +
         std::to_string(options_.min_keyframes) + ": not tuned yet");
    return;
  }
  const scene::CameraInfo& cam = frames.camera;
  const int width = std::min(options_.view_width, cam.image_width);
  const int height = std::max(
      1, static_cast<int>(std::lround(static_cast<double>(width) * cam.image_height / cam.image_width)));
  refine::LeaveOneOutOptions loo;
  loo.folds = options_.folds;
  loo.fusion_scene = options_.scene;
  const std::vector<model::RefineSample> samples = refine::MakeLeaveOneOutSamples(
      frames, scene::CenterCropResizeCamera(cam, width, height), loo);
  if (samples.empty()) {
    skip("no keyframe sees the surface fused from the others (" +
         std::to_string(frames.frames.size()) + " keyframes): not tuned");
    return;
  }
  model::RefineTrainOptions train = options_.train;
  train.steps = options_.steps_per_round;
  const model::RefineFitReport fit =
      refiner_->refiner().Fit(samples, train, [this] {
        std::lock_guard<std::mutex> lock(mutex_);
        return stopping_;
      });
  if (fit.stopped) return;  // shutting down: the last written net stays the newest
  uint64_t round = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    round = stats_.rounds + 1;
  }
  const std::string path = NetPath(round);
  refiner_->refiner().Save(path, "online leave-one-out on " + std::to_string(frames.frames.size()) +
                                     " keyframes (" + std::to_string(samples.size()) + " samples)");
  std::error_code ec;  // round - 1's file stays: the mapper may be copying it
  if (round >= 2) fs::remove(NetPath(round - 2), ec);
  std::lock_guard<std::mutex> lock(mutex_);
  latest_ = {path, fit.total_steps};
  ++stats_.rounds;
  stats_.total_steps = fit.total_steps;
  stats_.last_samples = static_cast<int>(samples.size());
  stats_.first_loss = fit.first_loss;
  stats_.last_loss = fit.last_loss;
  stats_.last_round_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  stats_.last_error.clear();
  cv_.notify_all();
}

}  // namespace p2i::trainer
