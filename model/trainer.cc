/// @file trainer.cc
/// @brief Two-phase P2I-NET training, CNN-baseline regression, checkpoints, divergence guard.
#include "model/trainer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <torch/torch.h>

#include "model/batch_sampler.h"
#include "model/checkpoint.h"
#include "model/data_parallel.h"
#include "model/densify.h"
#include "model/losses.h"
#include "model/metrics.h"
#include "model/networks.h"
#include "model/pose_dependence.h"
#include "model/pose_spacing.h"
#include "scene/capture.h"
#include "scene/image_ops.h"

namespace p2i::model {

namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

std::array<double, 7> PoseArray(const scene::Pose& p) {
  const auto v = p.ToVector7();
  return {v[0], v[1], v[2], v[3], v[4], v[5], v[6]};
}

// A fresh start's pose normaliser: the bounds and principal rotation of every training frame's
// pose (densified views included).
PoseNormalizer FreshNormalizer(const scene::RgbdDataset& train) {
  std::vector<std::array<double, 7>> poses;
  for (const auto& f : train.frames) poses.push_back(PoseArray(f.pose));
  return PoseNormalizer::FromPoses(poses);
}

// Frames -> images in [-1, 1] (N x C x R x R), normalised poses (N x 7), and the RGB ground
// truth at the training resolution (for PSNR).
struct Prepared {
  torch::Tensor images;
  torch::Tensor poses;
  std::vector<cv::Mat> rgb;
};

Prepared Prepare(const std::vector<scene::RgbdSample>& frames, const P2iConfig& config,
                 const PoseNormalizer& norm, size_t max_frames) {
  const int r = config.resolution;
  const size_t n = std::min(frames.size(), max_frames);
  Prepared p;
  p.images = torch::empty({static_cast<int64_t>(n), config.Channels(), r, r});
  p.poses = torch::empty({static_cast<int64_t>(n), 7});
  for (size_t i = 0; i < n; ++i) {
    // Evenly spread when only a subset is used.
    const auto& f = frames[n == frames.size() ? i : i * frames.size() / n];
    if (f.rgb.empty() || f.rgb.type() != CV_8UC3)
      throw std::invalid_argument("training frame '" + f.id + "' has no CV_8UC3 rgb image");
    if (config.depth && (f.depth.empty() || f.depth.type() != CV_32FC1))
      throw std::invalid_argument("training frame '" + f.id +
                                  "' has no CV_32FC1 depth image; set depth: false for RGB");
    scene::RgbdSample s = f;
    if (!config.depth) s.depth = cv::Mat();
    s = scene::CenterCropResizeSample(s, r, r);
    cv::Mat rgb = s.rgb.isContinuous() ? s.rgb : s.rgb.clone();
    p.rgb.push_back(rgb);
    auto t = torch::from_blob(rgb.data, {r, r, 3}, torch::kUInt8).permute({2, 0, 1}).to(torch::kFloat);
    p.images[i].slice(0, 0, 3).copy_(t / 127.5 - 1.0);
    if (config.depth) {
      cv::Mat d = s.depth.isContinuous() ? s.depth : s.depth.clone();
      auto td = torch::from_blob(d.data, {r, r}, torch::kFloat).clone();
      td = torch::nan_to_num(td, 0.0, 0.0, 0.0);
      p.images[i][3].copy_((td / config.depth_max).clamp(0.0, 1.0) * 2.0 - 1.0);
    }
    const auto np = norm.Normalize(PoseArray(f.pose));
    for (int k = 0; k < 7; ++k) p.poses[i][k] = np[k];
  }
  return p;
}

cv::Mat ToRgb8(const torch::Tensor& image) {  // C x R x R in [-1, 1]
  auto t = ((image.slice(0, 0, 3).clamp(-1, 1) + 1.0) * 127.5)
               .round()
               .to(torch::kUInt8)
               .permute({1, 2, 0})
               .contiguous();
  cv::Mat out(static_cast<int>(t.size(0)), static_cast<int>(t.size(1)), CV_8UC3);
  std::memcpy(out.data, t.data_ptr<uint8_t>(), t.numel());
  return out;
}

std::string FormatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--:--";
  const int s = static_cast<int>(seconds);
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%d:%02d:%02d", s / 3600, (s / 60) % 60, s % 60);
  return buf;
}

// Thrown inside a step when the guard sees a bad loss.
struct Divergence {
  std::string why;
};

// What one training step hands to the bookkeeping after it: the log line and the progress text.
struct StepOutcome {
  json line;
  std::string losses;
};

// Validation figures on the held-out frames.
struct Validation {
  double psnr = 0.0;
  double pose_dependence = std::nan("");
};

// One Trainer::Run call: set-up (inputs, checkpoint/warm start, networks, data), the phases, the
// report. Named steps, each a screen or less.
class TrainingRun {
 public:
  TrainingRun(const P2iConfig& config, const TrainerOptions& options)
      : config_(config), options_(options) {}

  TrainReport Execute(const scene::RgbdDataset& train, const scene::RgbdDataset& val);

 private:
  // --- set-up
  void CheckRequest(const scene::RgbdDataset& train) const;
  std::string FindSource(CheckpointMeta* source);
  void CheckShape(const P2iConfig& a, const std::string& path, bool warm) const;
  void ResolveFourierBands(const scene::RgbdDataset& train, bool fresh);
  void BuildNetworks();
  void InitialiseState(const std::string& warm_from, const CheckpointMeta& source,
                       const scene::RgbdDataset& train);
  double MeanImagePsnr() const;
  void LogStart(const scene::RgbdDataset& train, const std::string& warm_from, double mean_psnr);
  TrainReport Finish(TrainReport report);
  // --- steps
  int PhaseOne(int target);
  StepOutcome BaselineStep(int step, const torch::Tensor& real, const torch::Tensor& y);
  StepOutcome AdversarialStep(int step, const torch::Tensor& real, const torch::Tensor& y);
  void ExtraDiscriminatorSteps(int step);
  int PhaseTwo(int target);
  StepOutcome EnetStep(int step, const torch::Tensor& generated, const torch::Tensor& real);
  void AfterStep(int phase, int done, int target, const StepOutcome& outcome, const char* name);
  // --- helpers
  void ApplyLearningRates();
  /// Phase 1's learning-rate factor before `step` of `target` (config lr_decay_steps).
  void DecayLearningRates(int step, int target);
  void Save();
  void Rollback(const std::string& why);
  CheckpointMeta LoadRollbackPoint();
  void ShareNormalizer(const scene::RgbdDataset& train, bool fresh);
  void ReduceGradients(torch::optim::Optimizer& optimizer);
  void Log(const json& line);
  void Progress(const char* phase, int step, int target, const std::string& losses);
  Validation Validate(bool use_enet);
  torch::Tensor BatchIndices(int phase, int step) const;
  void CheckLoss(const torch::Tensor& loss, const char* what, int step);
  void TrackLoss(double magnitude);
  void UpdateEma();
  /// Between steps: true (after saving a checkpoint at the current step) when should_stop says so.
  bool StopNow();

  P2iConfig config_;
  TrainerOptions options_;
  std::string checkpoint_path_;
  bool load_ = false;  // resume or phase 2: the checkpoint in out_dir
  std::unique_ptr<Networks> nets_;
  std::unique_ptr<torch::optim::Adam> opt_g_, opt_d_, opt_e_;
  CheckpointMeta meta_;
  Prepared train_, val_;
  // Training frames by kind, for densify_real_share: captured, and densified (model/densify.h).
  std::vector<int64_t> captured_, densified_;
  std::ofstream log_;
  double ema_ = -1.0;
  double decay_ = 1.0;  // phase 1's learning-rate factor (config lr_decay_steps)
  Validation last_val_;
  // fourier_bands: auto on a fresh start: the captured frames' median neighbour distance in the
  // normalised pose input (NaN otherwise).
  double pose_spacing_ = std::numeric_limits<double>::quiet_NaN();
  bool injected_ = false;
  bool stopped_ = false;
  std::string diverged_;  // data-parallel: this rank's divergence, decided at the next all-reduce
  Clock::time_point phase_start_;
  int phase_start_step_ = 0;
  Clock::time_point last_progress_;
  std::shared_ptr<DataParallel> dp_;  // data-parallel ranks (null = one process)
};

void TrainingRun::ApplyLearningRates() {
  auto set = [&](torch::optim::Adam* opt, double lr) {
    if (opt == nullptr) return;
    for (auto& group : opt->param_groups())
      static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr * meta_.lr_scale);
  };
  set(opt_g_.get(), config_.lr_g * decay_);
  set(opt_d_.get(), config_.lr_d * decay_);
  set(opt_e_.get(), config_.lr_enet);
}

void TrainingRun::DecayLearningRates(int step, int target) {
  const int left = target - step;
  const double decay = left >= config_.lr_decay_steps
                           ? 1.0
                           : static_cast<double>(left) / config_.lr_decay_steps;
  if (decay == decay_) return;
  decay_ = decay;
  ApplyLearningRates();
}

void TrainingRun::Save() {
  if (dp_ && !dp_->IsWriter()) return;  // rank 0 writes the checkpoints
  SaveCheckpoint(checkpoint_path_, meta_, *nets_, {opt_g_.get(), opt_d_.get(), opt_e_.get()});
}

void TrainingRun::Rollback(const std::string& why) {
  if (meta_.rollbacks >= options_.max_rollbacks)
    throw std::runtime_error("training diverged " + std::to_string(meta_.rollbacks + 1) +
                             " times (" + why + "); giving up. Lower the learning rates in the "
                             "config or check the data.");
  const double new_scale = meta_.lr_scale * 0.5;
  const int rollbacks = meta_.rollbacks + 1;
  const int from1 = meta_.phase1_step, from2 = meta_.phase2_step;
  meta_ = LoadRollbackPoint();
  meta_.lr_scale = new_scale;
  meta_.rollbacks = rollbacks;
  ApplyLearningRates();
  ema_ = -1.0;
  Log({{"event", "rollback"},
       {"reason", why},
       {"from_phase1_step", from1},
       {"from_phase2_step", from2},
       {"to_phase1_step", meta_.phase1_step},
       {"to_phase2_step", meta_.phase2_step},
       {"lr_scale", meta_.lr_scale}});
  if (options_.progress)
    std::fprintf(stderr, "\ndivergence (%s): rolled back to the last checkpoint, lr x%.3g\n",
                 why.c_str(), meta_.lr_scale);
}

// The last checkpoint, rank 0's on every rank. Data-parallel: every rank gets here together
// (the decision rode in an all-reduce, ReduceGradients) and rank 0 broadcasts the file's bytes,
// so a rank whose out_dir holds an older copy (the trainer node's other ranks: theirs is the
// round's start) or none rolls back to the same weights, optimiser state, RNG and steps.
CheckpointMeta TrainingRun::LoadRollbackPoint() {
  std::string path = checkpoint_path_;
  if (dp_) {
    std::string bytes;
    if (dp_->IsWriter()) {
      std::ifstream in(checkpoint_path_, std::ios::binary);
      std::ostringstream ss;
      ss << in.rdbuf();
      bytes = ss.str();
    }
    bytes = dp_->BroadcastBytes(bytes, "the rollback to rank 0's checkpoint");
    if (bytes.empty())
      throw std::runtime_error("data-parallel rollback: rank 0 could not read " + checkpoint_path_);
    if (!dp_->IsWriter()) {
      path = options_.out_dir + "/rollback.rank" + std::to_string(dp_->Rank()) + ".pt";
      scene::WriteFileAtomic(path, bytes);
    }
  }
  CheckpointMeta meta = LoadCheckpoint(path, *nets_, {opt_g_.get(), opt_d_.get(), opt_e_.get()},
                                       /*restore_rng=*/true);
  if (path != checkpoint_path_) std::filesystem::remove(path);
  return meta;
}

// Data-parallel fresh start: the pose normaliser of every rank's frames, not this rank's alone
// (the trainer node's ranks hold disjoint shards; `p2i train`'s ranks read the same data, for
// which nothing changes). The translation bounds are all-reduced (the minima, and the negated
// maxima, by MIN); FromPoses of the two corner poses is FromPoses of the union of the ranks'
// frames, margin included. The reference rotation (PoseNormalizer::q_ref) is rank 0's principal
// rotation, broadcast: a sum over the ranks is not needed for a sign reference, only that every
// rank uses the same one. That every rank starts fresh, or none, ResolveFourierBands has agreed.
void TrainingRun::ShareNormalizer(const scene::RgbdDataset& train, bool fresh) {
  if (!dp_ || !fresh) return;
  std::vector<double> bounds(6, std::numeric_limits<double>::infinity());
  for (const auto& f : train.frames) {
    const auto p = PoseArray(f.pose);
    for (int a = 0; a < 3; ++a) {
      bounds[a] = std::min(bounds[a], p[a]);
      bounds[3 + a] = std::min(bounds[3 + a], -p[a]);
    }
  }
  bounds = dp_->Min(bounds, "the pose bounds of the ranks' frames");
  const std::array<double, 7> lo{bounds[0], bounds[1], bounds[2], 0, 0, 0, 1};
  const std::array<double, 7> hi{-bounds[3], -bounds[4], -bounds[5], 0, 0, 0, 1};
  // InitialiseState's fresh start set this rank's normaliser from its own frames: keep its q_ref.
  std::array<double, 4> q_ref = meta_.normalizer.q_ref;
  meta_.normalizer = PoseNormalizer::FromPoses({lo, hi});
  std::string bytes(sizeof(q_ref), '\0');
  std::memcpy(bytes.data(), q_ref.data(), sizeof(q_ref));
  bytes = dp_->BroadcastBytes(bytes, "rank 0's principal rotation of its frames");
  if (bytes.size() != sizeof(q_ref))
    throw std::runtime_error("data-parallel start: rank 0's principal rotation has " +
                             std::to_string(bytes.size()) + " bytes, expected " +
                             std::to_string(sizeof(q_ref)));
  std::memcpy(q_ref.data(), bytes.data(), sizeof(q_ref));
  meta_.normalizer.q_ref = q_ref;
}

// Between backward() and step(): the gradients' mean over the ranks, and their common verdict
// on divergence (CheckLoss's, carried in the same all-reduce): every rank throws Divergence
// and rolls back, or none does. One process: nothing to do (CheckLoss has thrown already).
void TrainingRun::ReduceGradients(torch::optim::Optimizer& optimizer) {
  if (!dp_) return;
  const bool mine = !diverged_.empty();
  const bool any = dp_->AverageGradients(optimizer, mine);
  if (!any) return;
  const std::string why = mine ? diverged_ : "a loss diverged on another rank";
  diverged_.clear();
  throw Divergence{why};
}

void TrainingRun::UpdateEma() {
  torch::NoGradGuard no_grad;
  // Warm-up: a plain running mean of all G's so far until it reaches the configured decay
  // (decay_t = (1 + t) / (2 + t)), so the random initialisation does not linger for
  // ~1/(1-decay) steps. (A shorter warm-up, (1 + t) / (10 + t) as TensorFlow's
  // ExponentialMovingAverage, was 0.6 dB worse at 500 steps: docs/MODEL.md.)
  const double updates = meta_.phase1_step + 1.0;
  const double decay = std::min(config_.g_ema, (1.0 + updates) / (2.0 + updates));
  auto src = nets_->g->named_parameters();
  for (auto& kv : nets_->g_ema->named_parameters())
    kv.value().mul_(decay).add_(src[kv.key()], 1.0 - decay);
}

bool TrainingRun::StopNow() {
  if (stopped_) return true;
  bool stop = options_.should_stop && options_.should_stop();
  if (dp_) stop = dp_->Any(stop);  // every rank stops at the same step
  if (!stop) return false;
  Save();
  stopped_ = true;
  Log({{"event", "stopped"}, {"phase1_step", meta_.phase1_step}, {"phase2_step", meta_.phase2_step}});
  if (options_.progress) std::fprintf(stderr, "\nstopped: checkpoint saved\n");
  return true;
}

void TrainingRun::Log(const json& line) {
  log_ << line.dump() << "\n";
  log_.flush();
}

void TrainingRun::Progress(const char* phase, int step, int target, const std::string& losses) {
  if (!options_.progress) return;
  const auto now = Clock::now();
  if (step != target && now - last_progress_ < std::chrono::milliseconds(250)) return;
  last_progress_ = now;
  const double elapsed = std::chrono::duration<double>(now - phase_start_).count();
  const double rate = elapsed > 0 ? (step - phase_start_step_) / elapsed : 0.0;
  const double eta = rate > 0 ? (target - step) / rate : -1.0;
  constexpr int kBar = 24;
  const int filled = target > 0 ? kBar * step / target : kBar;
  std::string bar(filled, '#');
  bar.resize(kBar, '.');
  char pd[48] = "";
  if (std::isfinite(last_val_.pose_dependence))
    std::snprintf(pd, sizeof(pd), " val %.2f dB pose-dep %.2f", last_val_.psnr,
                  last_val_.pose_dependence);
  std::fprintf(stderr, "\r%s [%s] %d/%d %s%s %.2f it/s ETA %s   ", phase, bar.c_str(), step,
               target, losses.c_str(), pd, rate, FormatDuration(eta).c_str());
  if (step == target) std::fprintf(stderr, "\n");
}

Validation TrainingRun::Validate(bool use_enet) {
  Validation v;
  if (val_.rgb.empty()) return v;
  torch::NoGradGuard no_grad;
  nets_->g->eval();
  if (use_enet) nets_->e->eval();
  double sum = 0.0;
  PoseDependence dependence;
  const int64_t n = val_.poses.size(0);
  for (int64_t i = 0; i < n; i += 16) {
    const int64_t j = std::min(n, i + 16);
    auto out = nets_->Serving()->forward(val_.poses.slice(0, i, j));
    if (use_enet) out = nets_->e->forward(out);
    for (int64_t k = i; k < j; ++k) {
      const cv::Mat rgb = ToRgb8(out[k - i]);
      sum += Psnr(rgb, val_.rgb[k]);
      dependence.Add(rgb, val_.rgb[k]);
    }
  }
  nets_->g->train();
  if (use_enet) nets_->e->train();
  v.psnr = sum / static_cast<double>(n);
  v.pose_dependence = dependence.Score();
  return v;
}

torch::Tensor TrainingRun::BatchIndices(int phase, int step) const {
  BatchDraw d;
  d.seed = config_.seed;
  d.phase = phase;
  d.step = step;
  d.batch_size = config_.batch_size;
  d.world = dp_ ? dp_->WorldSize() : 1;
  d.rank = dp_ ? dp_->Rank() : 0;
  // Past densify_steps (phase 1's G/D batches, 100 + k its extra D ones) and in phase 2: captured
  // frames only. Share 0 (or no densified frames): the uniform DrawBatch over all frames.
  const bool captured_only =
      config_.densify_steps >= 0 && (phase == 2 || step >= config_.densify_steps);
  const double share = captured_only ? 1.0 : config_.densify_real_share;
  return torch::tensor(DrawMixedBatch(d, captured_, densified_, share), torch::kLong);
}

// The divergence guard on one loss. One process: throws Divergence at once. Data-parallel: the
// verdict waits for this optimiser's all-reduce (ReduceGradients), which makes it every rank's
// (a rollback on one rank only would put the ranks' weights and collectives out of step).
void TrainingRun::CheckLoss(const torch::Tensor& loss, const char* what, int step) {
  (void)step;
  const double v = loss.item<double>();
  std::string why;
  if (!std::isfinite(v)) {
    why = std::string(what) + " is not finite";
  } else if (ema_ >= 0 && std::abs(v) > config_.explode_factor * std::max(ema_, 1.0)) {
    why = std::string(what) + " exploded to " + std::to_string(v);
  }
  if (why.empty()) return;
  if (!dp_) throw Divergence{why};
  if (diverged_.empty()) diverged_ = why;
}

void TrainingRun::TrackLoss(double magnitude) {
  ema_ = ema_ < 0 ? magnitude : 0.95 * ema_ + 0.05 * magnitude;
}

// Logging, validation (with the pose-dependence warning), checkpoint and progress after a step.
void TrainingRun::AfterStep(int phase, int done, int target, const StepOutcome& outcome,
                            const char* name) {
  if (done % 10 == 0 || done == target) Log(outcome.line);
  if (done % config_.val_every == 0 || done == target) {
    last_val_ = Validate(phase == 2);
    const double pd = last_val_.pose_dependence;
    Log({{"phase", phase},
         {"step", done},
         {"val_psnr", last_val_.psnr},
         {"pose_dependence", std::isfinite(pd) ? json(pd) : json(nullptr)}});
    const std::string warning = PoseDependenceWarning(pd);
    if (!warning.empty()) {
      Log({{"event", "warning"}, {"phase", phase}, {"step", done}, {"pose_dependence", pd},
           {"message", warning}});
      if (options_.progress) std::fprintf(stderr, "\n%s (step %d)\n", warning.c_str(), done);
    }
  }
  if (done % config_.checkpoint_every == 0 || done == target) Save();
  Progress(name, done, target, outcome.losses);
}

StepOutcome TrainingRun::BaselineStep(int step, const torch::Tensor& real, const torch::Tensor& y) {
  auto loss = RegressionLoss(nets_->g->forward(y), real);
  if (options_.inject_nan_at_step == step && !injected_) {
    injected_ = true;
    loss = loss * std::nan("");
  }
  CheckLoss(loss, "L2 loss", step);
  opt_g_->zero_grad();
  loss.backward();
  ReduceGradients(*opt_g_);
  opt_g_->step();
  const double v = loss.item<double>();
  TrackLoss(std::abs(v));
  StepOutcome o{{{"phase", 1}, {"step", step + 1}, {"loss", v}}, ""};
  char buf[64];
  std::snprintf(buf, sizeof(buf), "L2 %.4f", v);
  o.losses = buf;
  return o;
}

// d_steps > 1: extra D steps first, each on its own batch (a pure function of the step too),
// with fakes made without autograd.
void TrainingRun::ExtraDiscriminatorSteps(int step) {
  const LossWeights w = LossWeights::From(config_);
  for (int k = 1; k < config_.d_steps; ++k) {
    const auto idx_k = BatchIndices(100 + k, step);
    const auto y_k = train_.poses.index_select(0, idx_k);
    torch::Tensor fake_k;
    {
      torch::NoGradGuard no_grad;
      fake_k = nets_->g->forward(y_k);
    }
    auto& d = nets_->d;
    auto dl_k = DiscriminatorLoss(d->forward(train_.images.index_select(0, idx_k)),
                                  d->forward(fake_k), d->MapPose(y_k), y_k, w);
    CheckLoss(dl_k.total, "L_D", step);
    opt_d_->zero_grad();
    dl_k.total.backward();
    ReduceGradients(*opt_d_);
    opt_d_->step();
  }
}

StepOutcome TrainingRun::AdversarialStep(int step, const torch::Tensor& real,
                                         const torch::Tensor& y) {
  const LossWeights w = LossWeights::From(config_);
  auto& d = nets_->d;
  ExtraDiscriminatorSteps(step);
  // D step on a detached fake (G's forward is made once and reused by the G step).
  const auto fake = nets_->g->forward(y);
  const auto mp = d->MapPose(y);
  const bool r1 = config_.r1_gamma > 0;
  const auto real_in = r1 ? real.detach().requires_grad_(true) : real;
  const DOutput d_real = d->forward(real_in);
  auto dl = DiscriminatorLoss(d_real, d->forward(fake.detach()), mp, y, w);
  torch::Tensor r1_term;
  if (r1) {
    r1_term = R1Penalty(ProjectionScore(d_real, mp, w), real_in, config_.r1_gamma);
    dl.total = dl.total + r1_term;
  }
  if (options_.inject_nan_at_step == step && !injected_) {
    injected_ = true;
    dl.total = dl.total * std::nan("");
  }
  CheckLoss(dl.total, "L_D", step);
  opt_d_->zero_grad();
  dl.total.backward();
  ReduceGradients(*opt_d_);
  opt_d_->step();
  // G step through the updated D, frozen: only opt_g steps, so D's weight gradients are not
  // computed (the same G gradients; model_bench --profile shows the saving).
  GeneratorLossTerms gl;
  torch::Tensor recon;
  {
    FrozenScope frozen_d(*d);
    gl = GeneratorLoss(d->forward(fake), d->MapPose(y), y, w);
    if (config_.recon_weight > 0) {
      recon = ReconstructionLoss(fake, real);
      gl.total = gl.total + config_.recon_weight * recon;
    }
    CheckLoss(gl.total, "L_G", step);
    opt_g_->zero_grad();
    gl.total.backward();
  }
  ReduceGradients(*opt_g_);
  opt_g_->step();
  if (nets_->g_ema) UpdateEma();
  const double ld = dl.total.item<double>(), lg = gl.total.item<double>();
  TrackLoss(std::abs(ld) + std::abs(lg));
  StepOutcome o{{{"phase", 1}, {"step", step + 1}}, ""};
  o.line["loss_d"] = ld;
  o.line["loss_g"] = lg;
  o.line["pro"] = dl.pro.item<double>();
  o.line["pe_real"] = dl.pe_real.item<double>();
  o.line["pe_fake"] = dl.pe_fake.item<double>();
  o.line["g_adv"] = gl.adv.item<double>();
  o.line["g_pose"] = gl.pose.item<double>();
  if (recon.defined()) o.line["g_recon"] = recon.item<double>();
  if (r1_term.defined()) o.line["d_r1"] = r1_term.item<double>();
  char buf[96];
  std::snprintf(buf, sizeof(buf), "L_D %.3f L_G %.3f", ld, lg);
  o.losses = buf;
  return o;
}

int TrainingRun::PhaseOne(int target) {
  phase_start_ = Clock::now();
  phase_start_step_ = meta_.phase1_step;
  const char* name = config_.IsBaseline() ? "cnn" : "phase1";
  while (meta_.phase1_step < target) {
    if (StopNow()) break;
    const int step = meta_.phase1_step;
    const auto idx = BatchIndices(1, step);
    const auto real = train_.images.index_select(0, idx);
    const auto y = train_.poses.index_select(0, idx);
    if (config_.lr_decay_steps > 0) DecayLearningRates(step, target);
    StepOutcome outcome;
    try {
      outcome = config_.IsBaseline() ? BaselineStep(step, real, y) : AdversarialStep(step, real, y);
    } catch (const Divergence& div) {
      Rollback(div.why);
      continue;
    }
    meta_.phase1_step = step + 1;
    if (config_.lr_decay_steps > 0) outcome.line["lr_decay"] = decay_;
    AfterStep(1, meta_.phase1_step, target, outcome, name);
  }
  return meta_.phase1_step;
}

StepOutcome TrainingRun::EnetStep(int step, const torch::Tensor& generated,
                                  const torch::Tensor& real) {
  const LossWeights w = LossWeights::From(config_);
  auto el = EnetLoss(nets_->e->forward(generated), real, w);
  CheckLoss(el.total, "L_ENET", step);
  opt_e_->zero_grad();
  el.total.backward();
  ReduceGradients(*opt_e_);
  opt_e_->step();
  const double v = el.total.item<double>();
  TrackLoss(std::abs(v));
  StepOutcome o{{{"phase", 2},
                 {"step", step + 1},
                 {"loss_enet", v},
                 {"pixel", el.pixel.item<double>()},
                 {"edge", el.edge.item<double>()}},
                ""};
  char buf[64];
  std::snprintf(buf, sizeof(buf), "L_ENET %.3f", v);
  o.losses = buf;
  return o;
}

int TrainingRun::PhaseTwo(int target) {
  nets_->g->eval();
  for (auto& p : nets_->g->parameters()) p.set_requires_grad(false);
  phase_start_ = Clock::now();
  phase_start_step_ = meta_.phase2_step;
  ema_ = -1.0;
  while (meta_.phase2_step < target) {
    if (StopNow()) break;
    const int step = meta_.phase2_step;
    const auto idx = BatchIndices(2, step);
    const auto real = train_.images.index_select(0, idx);
    const auto y = train_.poses.index_select(0, idx);
    torch::Tensor generated;
    {
      torch::NoGradGuard no_grad;  // the frozen G that will render
      generated = nets_->Serving()->forward(y);
    }
    StepOutcome outcome;
    try {
      outcome = EnetStep(step, generated, real);
    } catch (const Divergence& div) {
      Rollback(div.why);
      continue;
    }
    meta_.phase2_step = step + 1;
    AfterStep(2, meta_.phase2_step, target, outcome, "phase2");
  }
  for (auto& p : nets_->g->parameters()) p.set_requires_grad(true);
  nets_->g->train();
  return meta_.phase2_step;
}

void TrainingRun::CheckRequest(const scene::RgbdDataset& train) const {
  if (train.frames.size() < 2)
    throw std::invalid_argument("training needs at least 2 frames, got " +
                                std::to_string(train.frames.size()));
  if (load_ && !std::filesystem::exists(checkpoint_path_))
    throw std::runtime_error(std::string(options_.resume ? "--resume" : "phase 2") + " needs " +
                             checkpoint_path_ + ", which does not exist: run phase 1 first");
  if (options_.phase == 2 && (config_.IsBaseline() || !config_.enet))
    throw std::invalid_argument("phase 2 trains ENET, but config '" + config_.name +
                                "' has none (cnn_baseline or enet: false)");
}

void TrainingRun::CheckShape(const P2iConfig& a, const std::string& path, bool warm) const {
  if (a.resolution != config_.resolution || a.Channels() != config_.Channels() ||
      a.model != config_.model || a.GeneratorWidths() != config_.GeneratorWidths() ||
      a.g_fc_width != config_.g_fc_width || a.g_norm != config_.g_norm ||
      a.pose_encoding != config_.pose_encoding || a.PoseInputs() != config_.PoseInputs())
    throw std::runtime_error("checkpoint " + path + " was trained with config '" + a.name +
                             "' of another shape (resolution, channels, model, G widths, "
                             "g_fc_width, g_norm or pose_encoding differ from '" + config_.name +
                             "')");
  if (warm && a.enet && config_.enet &&
      (a.enet_width != config_.enet_width || a.enet_blocks != config_.enet_blocks))
    throw std::runtime_error("checkpoint " + path + " has an ENET of another shape (enet_width, "
                             "enet_blocks) than config '" + config_.name + "'");
}

// The warm-start file ("" = none): an inference checkpoint in out_dir (resume) or
// options_.init_from (no resume). Checks the source's shape; on resume adopts its config with
// the given schedule.
std::string TrainingRun::FindSource(CheckpointMeta* source) {
  std::string warm_from;
  if (load_) {
    *source = ReadCheckpointMeta(checkpoint_path_);
    if (source->inference_only) warm_from = checkpoint_path_;
  } else if (!options_.init_from.empty()) {
    *source = ReadCheckpointMeta(options_.init_from);
    warm_from = options_.init_from;
  }
  if (!load_ && warm_from.empty()) return warm_from;
  // fourier_bands: auto resumes and warm-starts with the count the checkpoint was trained with.
  if (config_.AutoFourierBands() && source->config.pose_encoding == "fourier")
    config_.fourier_bands = source->config.fourier_bands;
  CheckShape(source->config, load_ ? checkpoint_path_ : warm_from, !warm_from.empty());
  if (load_) {  // resume: the checkpoint's config, the given schedule
    const P2iConfig schedule = config_;
    config_ = source->config;
    config_.steps_phase1 = schedule.steps_phase1;
    config_.steps_phase2 = schedule.steps_phase2;
    config_.lr_decay_steps = schedule.lr_decay_steps;
    config_.val_every = schedule.val_every;
    config_.checkpoint_every = schedule.checkpoint_every;
  }
  return warm_from;
}

// fourier_bands: auto on a fresh start: the band count for the captured training frames' median
// neighbour distance in the normalised pose input (model/pose_spacing.h; densified views are
// the method's own fill-in, not the capture's spacing). Data-parallel: rank 0's count on every
// rank, so all build the same G (the trainer node's ranks hold disjoint shards, whose spacings
// differ); every rank takes part in the broadcast whether or not its config says auto. First,
// the ranks agree that all start fresh or none does (ShareNormalizer relies on it).
void TrainingRun::ResolveFourierBands(const scene::RgbdDataset& train, bool fresh) {
  if (dp_) dp_->Agree(fresh ? 1 : 0, "a fresh start (no checkpoint to resume, no --init-from)");
  if (!fresh) return;
  const bool choose = config_.AutoFourierBands();
  if (choose) {
    const PoseNormalizer norm = FreshNormalizer(train);
    std::vector<std::array<float, 7>> inputs;
    for (const auto& f : train.frames)
      if (!IsDensified(f)) inputs.push_back(norm.Normalize(PoseArray(f.pose)));
    pose_spacing_ = MedianNeighbourDistance(inputs);
    config_.fourier_bands = FourierBandsForSpacing(pose_spacing_);
  }
  if (!dp_) return;
  const std::string bytes =
      dp_->BroadcastBytes(std::to_string(config_.fourier_bands), "rank 0's Fourier band count");
  if (choose) config_.fourier_bands = std::stoi(bytes);
}

void TrainingRun::BuildNetworks() {
  torch::manual_seed(config_.seed);
  nets_ = std::make_unique<Networks>(config_);
  const auto adam = [&](double lr) {
    return torch::optim::AdamOptions(lr).betas({config_.beta1, config_.beta2});
  };
  opt_g_ = std::make_unique<torch::optim::Adam>(nets_->g->parameters(), adam(config_.lr_g));
  if (nets_->d)
    opt_d_ = std::make_unique<torch::optim::Adam>(nets_->d->parameters(), adam(config_.lr_d));
  if (nets_->e)
    opt_e_ = std::make_unique<torch::optim::Adam>(nets_->e->parameters(), adam(config_.lr_enet));
}

void TrainingRun::InitialiseState(const std::string& warm_from, const CheckpointMeta& source,
                                  const scene::RgbdDataset& train) {
  if (!warm_from.empty()) {
    // G (and ENET when both have one) from the file; D and the optimisers stay fresh.
    const bool with_enet = nets_->e && source.config.enet;
    LoadWeights(warm_from, *nets_, with_enet);
    meta_ = source;
    meta_.config = config_;
    meta_.inference_only = false;
    meta_.lr_scale = 1.0;
    meta_.rollbacks = 0;
    if (!with_enet) meta_.phase2_step = 0;
  } else if (load_) {
    meta_ = LoadCheckpoint(checkpoint_path_, *nets_, {opt_g_.get(), opt_d_.get(), opt_e_.get()},
                           /*restore_rng=*/true);
    meta_.config = config_;
  } else {
    meta_.config = config_;
    meta_.normalizer = FreshNormalizer(train);
    meta_.camera = scene::CenterCropResizeCamera(train.camera, config_.resolution,
                                                 config_.resolution);
  }
  ApplyLearningRates();
}

// Mean training image as a predictor: the floor a model must beat (0 without validation).
double TrainingRun::MeanImagePsnr() const {
  if (val_.rgb.empty()) return 0.0;
  cv::Mat sum = cv::Mat::zeros(config_.resolution, config_.resolution, CV_64FC3);
  for (const auto& m : train_.rgb) cv::accumulate(m, sum);
  cv::Mat mean;
  sum.convertTo(mean, CV_8UC3, 1.0 / train_.rgb.size());
  double s = 0;
  for (const auto& m : val_.rgb) s += Psnr(mean, m);
  return s / val_.rgb.size();
}

void TrainingRun::LogStart(const scene::RgbdDataset& train, const std::string& warm_from,
                           double mean_psnr) {
  log_.open(options_.out_dir + (dp_ && dp_->Rank() > 0 ? "/train_log.rank" +
                                   std::to_string(dp_->Rank()) + ".jsonl" : "/train_log.jsonl"),
            std::ios::app);
  if (!log_) throw std::runtime_error("cannot open " + options_.out_dir + "/train_log.jsonl");
  Log({{"event", "start"},
       {"config", config_.name},
       {"model", config_.model},
       {"resume", load_ && warm_from.empty()},
       {"warm_start", warm_from},
       {"phase1_step", meta_.phase1_step},
       {"phase2_step", meta_.phase2_step},
       {"train_frames", train.frames.size()},
       {"densified_frames", densified_.size()},
       {"densify_real_share", config_.densify_real_share},
       {"densify_steps", config_.densify_steps},
       {"fourier_bands", config_.pose_encoding == "fourier" ? json(config_.fourier_bands)
                                                            : json(nullptr)},
       {"pose_spacing", std::isfinite(pose_spacing_) ? json(pose_spacing_) : json(nullptr)},
       {"val_frames", val_.rgb.size()},
       {"threads", options_.threads},
       {"mean_image_val_psnr", mean_psnr}});
}

TrainReport TrainingRun::Finish(TrainReport report) {
  Save();
  if (dp_) dp_->WriteStats(options_.out_dir);
  Log({{"event", "end"},
       {"phase1_step", meta_.phase1_step},
       {"phase2_step", meta_.phase2_step},
       {"rollbacks", meta_.rollbacks},
       {"val_psnr", last_val_.psnr},
       {"pose_dependence", std::isfinite(last_val_.pose_dependence)
                               ? json(last_val_.pose_dependence)
                               : json(nullptr)}});
  report.phase1_steps = meta_.phase1_step;
  report.phase2_steps = meta_.phase2_step;
  report.rollbacks = meta_.rollbacks;
  report.stopped = stopped_;
  report.val_psnr = last_val_.psnr;
  report.val_pose_dependence = last_val_.pose_dependence;
  report.checkpoint_path = checkpoint_path_;
  report.log_path = options_.out_dir + "/train_log.jsonl";
  return report;
}

TrainReport TrainingRun::Execute(const scene::RgbdDataset& train, const scene::RgbdDataset& val) {
  checkpoint_path_ = Trainer::CheckpointPath(options_.out_dir);
  load_ = options_.resume || options_.phase == 2;
  CheckRequest(train);
  std::filesystem::create_directories(options_.out_dir);
  torch::set_num_threads(options_.threads);
  CheckpointMeta source;
  const std::string warm_from = FindSource(&source);
  const bool fresh = !load_ && warm_from.empty();
  dp_ = DataParallel::For(options_.distributed);
  ResolveFourierBands(train, fresh);
  BuildNetworks();
  InitialiseState(warm_from, source, train);
  if (dp_) dp_->Start(&meta_.phase1_step, &meta_.phase2_step, *nets_);  // same start everywhere
  ShareNormalizer(train, fresh);
  train_ = Prepare(train.frames, config_, meta_.normalizer, train.frames.size());
  for (size_t i = 0; i < train.frames.size(); ++i)
    (IsDensified(train.frames[i]) ? densified_ : captured_).push_back(static_cast<int64_t>(i));
  val_ = Prepare(val.frames, config_, meta_.normalizer, static_cast<size_t>(options_.max_val_frames));
  TrainReport report;
  report.mean_image_val_psnr = MeanImagePsnr();
  LogStart(train, warm_from, report.mean_image_val_psnr);
  Save();  // the first rollback point
  const bool run1 = options_.phase != 2;
  const bool run2 = options_.phase != 1 && !config_.IsBaseline() && config_.enet;
  if (run1) PhaseOne(options_.steps >= 0 ? options_.steps : config_.steps_phase1);
  const int target2 = options_.steps_phase2 >= 0 ? options_.steps_phase2
                      : options_.steps >= 0     ? options_.steps
                                                : config_.steps_phase2;
  if (run2 && !stopped_) PhaseTwo(target2);
  return Finish(report);
}

}  // namespace

void TrainerOptions::Validate() const {
  if (out_dir.empty()) throw std::invalid_argument("TrainerOptions: out_dir is empty");
  if (phase < 0 || phase > 2) throw std::invalid_argument("TrainerOptions: phase must be 0, 1 or 2");
  if (threads < 1) throw std::invalid_argument("TrainerOptions: threads must be >= 1");
  if (max_val_frames < 1) throw std::invalid_argument("TrainerOptions: max_val_frames must be >= 1");
  if (max_rollbacks < 0) throw std::invalid_argument("TrainerOptions: max_rollbacks must be >= 0");
  distributed.Validate();
}

Trainer::Trainer(P2iConfig config, TrainerOptions options)
    : config_(std::move(config)), options_(std::move(options)) {
  config_.Validate();
  options_.Validate();
}

Trainer::~Trainer() = default;

std::string Trainer::CheckpointPath(const std::string& out_dir) {
  return out_dir + "/checkpoint.pt";
}

TrainReport Trainer::Run(const scene::RgbdDataset& train, const scene::RgbdDataset& val) {
  TrainingRun run(config_, options_);
  return run.Execute(train, val);
}

}  // namespace p2i::model
