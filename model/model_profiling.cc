/// @file model_profiling.cc
/// @brief Benchmark helpers (see model_profiling.h).
#include "model/model_profiling.h"

#include <algorithm>
#include <chrono>
#include <optional>

#include <torch/torch.h>

#include "model/checkpoint.h"
#include "model/losses.h"
#include "model/networks.h"

namespace p2i::model {

namespace {
using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// D's forward MACs for one image (convs, attention and heads), computed from its shape.
double DiscriminatorMacs(const P2iConfig& c) {
  double macs = 0;
  int cin = c.Channels(), width = c.d_base_width, side = c.resolution;
  while (side > 4) {
    side /= 2;
    const double px = static_cast<double>(side) * side;
    macs += 16.0 * cin * width * px;
    if (c.attention && side <= c.attention_max_res) {
      const double inner = std::max(1, width / 8);
      macs += px * width * (2 * inner + width) + px * px * (inner + width);
    }
    cin = width;
    width = std::min(width * 2, c.d_max_width);
  }
  macs += 9.0 * cin * c.latent_dim * 16;
  macs += c.latent_dim + 7.0 * c.mapping_width + 2.0 * c.mapping_width * c.latent_dim + 7.0 * c.mapping_width;
  return macs;
}
}  // namespace

double MeasureMatmulFlopRate(int n, int threads, int reps) {
  torch::set_num_threads(threads);
  torch::NoGradGuard ng;
  auto a = torch::rand({n, n}), b = torch::rand({n, n});
  auto c = torch::mm(a, b);  // warm-up
  double best = 1e30;
  for (int i = 0; i < reps; ++i) {
    const auto t0 = Clock::now();
    c = torch::mm(a, b);
    best = std::min(best, Seconds(t0, Clock::now()));
  }
  return 2.0 * n * static_cast<double>(n) * n / best;
}

double TimeTrainingStep(const P2iConfig& config, int phase, int steps, int threads,
                        bool freeze_d) {
  torch::set_num_threads(threads);
  torch::manual_seed(config.seed);
  Networks nets(config);
  const LossWeights w = LossWeights::From(config);
  const int b = config.batch_size, r = config.resolution;
  auto real = torch::rand({b, config.Channels(), r, r}) * 2 - 1;
  auto y = torch::rand({b, 7}) * 2 - 1;
  torch::optim::Adam opt_g(nets.g->parameters(), torch::optim::AdamOptions(1e-4));
  std::unique_ptr<torch::optim::Adam> opt_d, opt_e;
  if (nets.d) opt_d = std::make_unique<torch::optim::Adam>(nets.d->parameters(), torch::optim::AdamOptions(1e-4));
  if (nets.e) opt_e = std::make_unique<torch::optim::Adam>(nets.e->parameters(), torch::optim::AdamOptions(1e-4));
  if (phase == 2 && !nets.e) return 0.0;
  auto step = [&]() {
    if (phase == 2) {
      torch::Tensor gen;
      {
        torch::NoGradGuard ng;
        gen = nets.g->forward(y);
      }
      auto l = EnetLoss(nets.e->forward(gen), real, w);
      opt_e->zero_grad();
      l.total.backward();
      opt_e->step();
    } else if (config.IsBaseline()) {
      auto l = RegressionLoss(nets.g->forward(y), real);
      opt_g.zero_grad();
      l.backward();
      opt_g.step();
    } else {
      auto fake = nets.g->forward(y);
      auto dl = DiscriminatorLoss(nets.d->forward(real), nets.d->forward(fake.detach()),
                                  nets.d->MapPose(y), y, w);
      opt_d->zero_grad();
      dl.total.backward();
      opt_d->step();
      std::optional<FrozenScope> frozen_d;  // as the trainer's G step
      if (freeze_d) frozen_d.emplace(*nets.d);
      auto gl = GeneratorLoss(nets.d->forward(fake), nets.d->MapPose(y), y, w);
      opt_g.zero_grad();
      gl.total.backward();
      opt_g.step();
    }
  };
  step();
  std::vector<double> times;
  for (int i = 0; i < std::max(1, steps); ++i) {
    const auto t0 = Clock::now();
    step();
    times.push_back(Seconds(t0, Clock::now()));
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

namespace {

/// The names of the sections StepSectionTimes measures, in its order.
const std::vector<std::string>& StepSectionNames() {
  static const std::vector<std::string> kNames = {"G forward",        "D fwd reals",
                                                  "D fwd fakes (D)",  "L_D + D backward",
                                                  "D Adam",           "D fwd fakes (G)",
                                                  "L_G + G backward", "G Adam"};
  return kNames;
}

/// One adversarial training step (the trainer's D step, then its G step), timed per section
/// (StepSectionNames' order), in seconds.
std::vector<double> StepSectionTimes(Networks& nets, const torch::Tensor& real,
                                     const torch::Tensor& y, const LossWeights& w,
                                     torch::optim::Adam& opt_g, torch::optim::Adam& opt_d,
                                     bool freeze_d) {
  std::vector<double> t;
  auto tick = Clock::now();
  auto lap = [&] {
    const auto now = Clock::now();
    t.push_back(Seconds(tick, now));
    tick = now;
  };
  auto fake = nets.g->forward(y);
  lap();
  auto dr = nets.d->forward(real);
  lap();
  auto df = nets.d->forward(fake.detach());
  lap();
  auto dl = DiscriminatorLoss(dr, df, nets.d->MapPose(y), y, w);
  opt_d.zero_grad();
  dl.total.backward();
  lap();
  opt_d.step();
  lap();
  {
    std::optional<FrozenScope> frozen_d;  // as the trainer's G step
    if (freeze_d) frozen_d.emplace(*nets.d);
    auto dg = nets.d->forward(fake);
    lap();
    auto gl = GeneratorLoss(dg, nets.d->MapPose(y), y, w);
    opt_g.zero_grad();
    gl.total.backward();
    lap();
  }
  opt_g.step();
  lap();
  return t;
}

/// Seconds of D's attention forwards at their sizes (batch b), summed over `steps` runs after
/// one warm-up.
double AttentionSeconds(Networks& nets, const P2iConfig& config, int b, int steps) {
  double att = 0.0;
  int side = config.resolution, width = config.d_base_width;
  for (size_t k = 0; k < nets.d->blocks->size(); ++k) {
    side /= 2;
    if (nets.d->attention_index_[k] >= 0) {
      auto a = nets.d->attentions[nets.d->attention_index_[k]]->as<SelfAttention>();
      auto x = torch::randn({b, width, side, side});
      for (int i = 0; i <= steps; ++i) {
        const auto t0 = Clock::now();
        auto o = a->forward(x);
        if (i > 0) att += Seconds(t0, Clock::now());
      }
    }
    width = std::min(width * 2, config.d_max_width);
  }
  return att;
}

/// Seconds of the spectral-norm power iterations of all D's weights, summed over `steps` runs
/// after one warm-up.
double SpectralNormSeconds(Networks& nets, int steps) {
  double sn = 0.0;
  for (int i = 0; i <= steps; ++i) {
    const auto t0 = Clock::now();
    for (auto& m : nets.d->modules(/*include_self=*/false)) {
      if (auto* c = m->as<SNConv2d>()) (void)c->EffectiveWeight();
      if (auto* l = m->as<SNLinear>()) (void)l->EffectiveWeight();
    }
    if (i > 0) sn += Seconds(t0, Clock::now());
  }
  return sn;
}

}  // namespace

StepProfile ProfileTrainingStep(const P2iConfig& config, int steps, int threads,
                                bool freeze_d) {
  torch::set_num_threads(threads);
  torch::manual_seed(config.seed);
  StepProfile out;
  if (config.IsBaseline()) return out;
  Networks nets(config);
  const LossWeights w = LossWeights::From(config);
  const int b = config.batch_size, r = config.resolution;
  auto real = torch::rand({b, config.Channels(), r, r}) * 2 - 1;
  auto y = torch::rand({b, 7}) * 2 - 1;
  torch::optim::Adam opt_g(nets.g->parameters(), torch::optim::AdamOptions(1e-4));
  torch::optim::Adam opt_d(nets.d->parameters(), torch::optim::AdamOptions(1e-4));
  const std::vector<std::string>& names = StepSectionNames();
  std::vector<double> acc(names.size(), 0.0);
  for (int i = 0; i <= steps; ++i) {
    const std::vector<double> t = StepSectionTimes(nets, real, y, w, opt_g, opt_d, freeze_d);
    if (i == 0) continue;  // warm-up
    for (size_t k = 0; k < acc.size(); ++k) acc[k] += t[k];
  }
  for (size_t k = 0; k < acc.size(); ++k) {
    out.sections.push_back({names[k], acc[k] / std::max(1, steps)});
    out.total += acc[k] / std::max(1, steps);
  }
  // Apart: attention forward at its sizes, and the SN power iterations of D's weights.
  const double att = AttentionSeconds(nets, config, b, steps);
  const double sn = SpectralNormSeconds(nets, steps);
  out.sections.push_back({"(apart) attention fwd, all blocks, x3 per step", 3.0 * att / std::max(1, steps)});
  out.sections.push_back({"(apart) SN power iterations, x3 per step", 3.0 * sn / std::max(1, steps)});
  return out;
}

double TrainingStepFlops(const P2iConfig& config, int phase) {
  Generator g(config);
  const double gm = g->MacsPerView();
  double macs = 0;
  if (phase == 2) {
    if (config.IsBaseline() || !config.enet) return 0;
    Enhancer e(config);
    macs = gm + 3.0 * e->MacsPerView();
  } else if (config.IsBaseline()) {
    macs = 3.0 * gm;
  } else {
    // G fwd+bwd once; D: real + fake fwd/bwd in the D step, fake fwd/bwd in the G step.
    macs = 3.0 * gm + 3.0 * 3.0 * DiscriminatorMacs(config);
  }
  return 2.0 * macs * config.batch_size;
}

void WriteUntrainedCheckpoint(const P2iConfig& config, const std::string& path) {
  torch::manual_seed(config.seed);
  Networks nets(config);
  CheckpointMeta meta;
  meta.config = config;
  meta.phase2_step = nets.e ? 1 : 0;
  const double f = config.resolution * 0.9, c = (config.resolution - 1) / 2.0;
  meta.camera = scene::CameraInfo::Pinhole(config.resolution, config.resolution, f, f, c, c);
  SaveCheckpoint(path, meta, nets, {});
}

}  // namespace p2i::model
