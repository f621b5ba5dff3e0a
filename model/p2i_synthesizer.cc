/// @file p2i_synthesizer.cc
/// @brief P2iSynthesizer (see p2i_synthesizer.h).
#include "model/p2i_synthesizer.h"

#include <cstring>
#include <stdexcept>

#include <torch/torch.h>

#include "model/checkpoint.h"
#include "model/networks.h"

namespace p2i::model {

void SynthesizerOptions::Validate() const {
  if (threads < 1) throw std::invalid_argument("SynthesizerOptions: threads must be >= 1");
  if (stage != "auto" && stage != "g" && stage != "g+enet")
    throw std::invalid_argument("SynthesizerOptions: stage must be auto, g or g+enet, got '" +
                                stage + "'");
  if (!(min_valid_depth >= 0)) throw std::invalid_argument("SynthesizerOptions: min_valid_depth < 0");
}

struct P2iSynthesizer::Impl {
  CheckpointMeta meta;
  std::unique_ptr<Networks> nets;
  bool use_enet = false;
  SynthesizerOptions options;
  torch::Tensor input;  // 1 x 7, reused for single renders
  std::string path;     // the checkpoint, named by the probe's refusals

  torch::Tensor Forward(const torch::Tensor& poses) {
    auto out = nets->g->forward(poses);
    if (use_enet) out = nets->e->forward(out);
    return out.clamp(-1.0, 1.0);
  }

  void FillPose(const scene::Pose& pose, float* dst) const {
    const auto v = pose.ToVector7();
    const auto n = meta.normalizer.Normalize({v[0], v[1], v[2], v[3], v[4], v[5], v[6]});
    std::memcpy(dst, n.data(), sizeof(float) * 7);
  }

  // image: C x R x R.
  scene::RgbdSample ToView(const torch::Tensor& image, const scene::Pose& pose) const {
    const int r = meta.config.resolution;
    scene::RgbdSample view;
    view.pose = pose;
    view.id = "p2i";
    auto rgb = ((image.slice(0, 0, 3) + 1.0) * 127.5)
                   .round()
                   .to(torch::kUInt8)
                   .permute({1, 2, 0})
                   .contiguous();
    view.rgb = cv::Mat(r, r, CV_8UC3);
    std::memcpy(view.rgb.data, rgb.data_ptr<uint8_t>(), rgb.numel());
    view.depth = cv::Mat(r, r, CV_32FC1, cv::Scalar(0.0f));
    if (meta.config.depth) {
      auto d = ((image[3] + 1.0) * 0.5 * meta.config.depth_max).contiguous();
      d = torch::where(d < options.min_valid_depth, torch::zeros_like(d), d);
      std::memcpy(view.depth.data, d.data_ptr<float>(), sizeof(float) * d.numel());
    }
    return view;
  }

  void ProbeOrThrow() {
    // One view at the middle of the training poses, looking along the identity rotation: weights
    // that are finite can still produce NaN or inf (overflow); such a model is refused here, at
    // start-up and before a hot swap, instead of serving garbage.
    c10::InferenceMode guard;
    const auto& n = meta.normalizer;
    const Eigen::Vector3d mid(0.5 * (n.t_min[0] + n.t_max[0]), 0.5 * (n.t_min[1] + n.t_max[1]),
                              0.5 * (n.t_min[2] + n.t_max[2]));
    FillPose(scene::Pose(mid, Eigen::Quaterniond::Identity()), input.data_ptr<float>());
    auto out = nets->g->forward(input);
    if (use_enet) out = nets->e->forward(out);
    const int r = meta.config.resolution;
    if (out.dim() != 4 || out.size(0) != 1 || out.size(2) != r || out.size(3) != r)
      throw std::runtime_error("checkpoint " + path + " refused: the probe view has shape " +
                               c10::str(out.sizes()) + ", expected 1 x C x " + std::to_string(r) +
                               " x " + std::to_string(r));
    const int64_t bad = out.numel() - torch::isfinite(out).sum().item<int64_t>();
    if (bad > 0)
      throw std::runtime_error("checkpoint " + path + " refused: its probe view (the middle "
                               "of the training poses) has " + std::to_string(bad) +
                               " non-finite pixel value(s): a diverged or damaged model");
  }
};

P2iSynthesizer::P2iSynthesizer(const std::string& checkpoint_path,
                               const SynthesizerOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.Validate();
  impl_->options = options;
  impl_->path = checkpoint_path;
  torch::set_num_threads(options.threads);
  impl_->meta = ReadCheckpointMeta(checkpoint_path);
  P2iConfig serving = impl_->meta.config;
  serving.g_ema = 0.0;  // one G: the file's serving one (its moving average when it has one)
  impl_->nets = std::make_unique<Networks>(serving, /*with_discriminator=*/false);
  LoadServingWeights(checkpoint_path, *impl_->nets);
  const bool enet_trained = impl_->nets->e && impl_->meta.phase2_step > 0;
  if (options.stage == "g+enet" && !enet_trained)
    throw std::runtime_error("checkpoint " + checkpoint_path +
                             " has no trained ENET (run phase 2: p2i train ... --phase 2)");
  impl_->use_enet = options.stage == "g+enet" || (options.stage == "auto" && enet_trained);
  impl_->nets->g->eval();
  if (impl_->nets->e) impl_->nets->e->eval();
  impl_->input = torch::zeros({1, 7});
  impl_->ProbeOrThrow();
}

P2iSynthesizer::~P2iSynthesizer() = default;

std::string P2iSynthesizer::Name() const {
  if (impl_->meta.config.IsBaseline()) return "cnn_baseline";
  return impl_->use_enet ? "p2i_net" : "p2i_net_g";
}

scene::CameraInfo P2iSynthesizer::Camera() const { return impl_->meta.camera; }

bool P2iSynthesizer::UsesEnet() const { return impl_->use_enet; }

scene::RgbdSample P2iSynthesizer::Render(const scene::Pose& pose) {
  c10::InferenceMode guard;
  impl_->FillPose(pose, impl_->input.data_ptr<float>());
  const auto out = impl_->Forward(impl_->input);
  return impl_->ToView(out[0], pose);
}

std::vector<scene::RgbdSample> P2iSynthesizer::RenderBatch(
    const std::vector<scene::Pose>& poses) {
  std::vector<scene::RgbdSample> views;
  if (poses.empty()) return views;
  c10::InferenceMode guard;
  auto input = torch::empty({static_cast<int64_t>(poses.size()), 7});
  for (size_t i = 0; i < poses.size(); ++i)
    impl_->FillPose(poses[i], input.data_ptr<float>() + 7 * i);
  const auto out = impl_->Forward(input);
  views.reserve(poses.size());
  for (size_t i = 0; i < poses.size(); ++i)
    views.push_back(impl_->ToView(out[static_cast<int64_t>(i)], poses[i]));
  return views;
}

int64_t P2iSynthesizer::ParameterCount() const {
  int64_t n = CountParameters(*impl_->nets->g);
  if (impl_->use_enet) n += CountParameters(*impl_->nets->e);
  return n;
}

double P2iSynthesizer::FlopsPerView() const {
  double macs = impl_->nets->g->MacsPerView();
  if (impl_->use_enet) macs += impl_->nets->e->MacsPerView();
  return 2.0 * macs;
}

std::unique_ptr<ViewSynthesizer> LoadSynthesizer(const std::string& checkpoint_path,
                                                 const SynthesizerOptions& options) {
  return std::make_unique<P2iSynthesizer>(checkpoint_path, options);
}

}  // namespace p2i::model
