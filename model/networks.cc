/// @file networks.cc
/// @brief P2I-NET modules (see networks.h).
#include "model/networks.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

namespace p2i::model {

namespace {

int Log2(int v) {
  int n = 0;
  while ((1 << n) < v) ++n;
  return n;
}

// One power iteration on the (out x rest) matrix w, updating u in place; returns W / sigma.
torch::Tensor SpectralNormalize(const torch::Tensor& weight, torch::Tensor& u, bool update) {
  const auto w = weight.reshape({weight.size(0), -1});
  torch::Tensor v;
  {
    torch::NoGradGuard no_grad;
    v = torch::nn::functional::normalize(torch::mv(w.t(), u),
                                         torch::nn::functional::NormalizeFuncOptions().dim(0).eps(1e-12));
    if (update) {
      auto new_u = torch::nn::functional::normalize(
          torch::mv(w, v), torch::nn::functional::NormalizeFuncOptions().dim(0).eps(1e-12));
      u.copy_(new_u);
    }
  }
  // A clone, as PyTorch does: a later forward updates u in place while this graph still needs it.
  const auto sigma = torch::dot(u.clone(), torch::mv(w, v));
  return weight / sigma;
}

}  // namespace

PoseNormalizer PoseNormalizer::FromPoses(const std::vector<std::array<double, 7>>& poses) {
  PoseNormalizer n;
  if (poses.empty()) return n;
  for (int a = 0; a < 3; ++a) {
    double lo = poses[0][a], hi = poses[0][a];
    for (const auto& p : poses) {
      lo = std::min(lo, p[a]);
      hi = std::max(hi, p[a]);
    }
    const double margin = std::max(0.05 * (hi - lo), 1e-3);
    n.t_min[a] = lo - margin;
    n.t_max[a] = hi + margin;
  }
  n.q_ref = PrincipalRotation(poses);
  return n;
}

std::array<double, 4> PoseNormalizer::PrincipalRotation(
    const std::vector<std::array<double, 7>>& poses) {
  if (poses.empty()) return {0, 0, 0, 1};
  Eigen::Matrix4d scatter = Eigen::Matrix4d::Zero();
  for (const auto& p : poses) {
    const Eigen::Vector4d q(p[3], p[4], p[5], p[6]);
    scatter += q * q.transpose();
  }
  // Eigenvalues in increasing order: the last column is the dominant eigenvector (unit norm).
  Eigen::Vector4d q = Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(scatter).eigenvectors().col(3);
  if (q[3] < 0) q = -q;
  return {q[0], q[1], q[2], q[3]};
}

std::array<float, 7> PoseNormalizer::Normalize(const std::array<double, 7>& pose) const {
  std::array<float, 7> out{};
  for (int a = 0; a < 3; ++a)
    out[a] = static_cast<float>(2.0 * (pose[a] - t_min[a]) / (t_max[a] - t_min[a]) - 1.0);
  double dot = 0;
  for (int i = 0; i < 4; ++i) dot += pose[3 + i] * q_ref[i];
  const double sign = dot < 0 ? -1.0 : 1.0;
  for (int a = 3; a < 7; ++a) out[a] = static_cast<float>(sign * pose[a]);
  return out;
}

SNLinearImpl::SNLinearImpl(int in, int out, bool sn) : sn_(sn) {
  torch::nn::Linear init(in, out);  // PyTorch's default initialisation
  weight = register_parameter("weight", init->weight.detach().clone());
  bias = register_parameter("bias", init->bias.detach().clone());
  u = register_buffer("u", torch::nn::functional::normalize(
                               torch::randn({out}),
                               torch::nn::functional::NormalizeFuncOptions().dim(0)));
}

torch::Tensor SNLinearImpl::EffectiveWeight() {
  return sn_ ? SpectralNormalize(weight, u, is_training()) : weight;
}

torch::Tensor SNLinearImpl::forward(const torch::Tensor& x) {
  return torch::nn::functional::linear(x, EffectiveWeight(), bias);
}

SNConv2dImpl::SNConv2dImpl(int in, int out, int kernel, int stride, int padding, bool sn)
    : stride_(stride), padding_(padding), sn_(sn) {
  torch::nn::Conv2d init(torch::nn::Conv2dOptions(in, out, kernel));
  weight = register_parameter("weight", init->weight.detach().clone());
  bias = register_parameter("bias", init->bias.detach().clone());
  u = register_buffer("u", torch::nn::functional::normalize(
                               torch::randn({out}),
                               torch::nn::functional::NormalizeFuncOptions().dim(0)));
}

torch::Tensor SNConv2dImpl::EffectiveWeight() {
  return sn_ ? SpectralNormalize(weight, u, is_training()) : weight;
}

torch::Tensor SNConv2dImpl::forward(const torch::Tensor& x) {
  return torch::conv2d(x, EffectiveWeight(), bias, stride_, padding_);
}

SelfAttentionImpl::SelfAttentionImpl(int channels, bool sn) {
  const int inner = std::max(1, channels / 8);
  f = register_module("f", SNConv2d(channels, inner, 1, 1, 0, sn));
  g = register_module("g", SNConv2d(channels, inner, 1, 1, 0, sn));
  h = register_module("h", SNConv2d(channels, channels, 1, 1, 0, sn));
  gamma = register_parameter("gamma", torch::zeros({1}));
}

torch::Tensor SelfAttentionImpl::forward(const torch::Tensor& x) {
  const auto b = x.size(0), c = x.size(1), n = x.size(2) * x.size(3);
  auto q = f->forward(x).reshape({b, -1, n});                 // b x c' x n
  auto k = g->forward(x).reshape({b, -1, n});                 // b x c' x n
  auto v = h->forward(x).reshape({b, c, n});                  // b x c x n
  auto attn = torch::softmax(torch::bmm(q.transpose(1, 2), k), -1);  // b x n x n
  auto o = torch::bmm(v, attn.transpose(1, 2)).reshape(x.sizes());
  return x + gamma * o;
}

GeneratorImpl::GeneratorImpl(const P2iConfig& config)
    : widths_(config.GeneratorWidths()),
      channels_(config.Channels()),
      pixel_norm_(config.g_norm == "pixel"),
      fourier_bands_(config.pose_encoding == "fourier" ? config.fourier_bands : 0) {
  fc1 = register_module("fc1", torch::nn::Linear(config.PoseInputs(), config.g_fc_width));
  fc2 = register_module("fc2", torch::nn::Linear(config.g_fc_width, 16 * widths_[0]));
  convs = register_module("convs", torch::nn::ModuleList());
  convs->push_back(torch::nn::Conv2d(
      torch::nn::Conv2dOptions(widths_[0], widths_[0], 3).padding(1)));
  for (size_t i = 1; i < widths_.size(); ++i)
    convs->push_back(torch::nn::Conv2d(
        torch::nn::Conv2dOptions(widths_[i - 1], widths_[i], 3).padding(1)));
  to_image = register_module(
      "to_image",
      torch::nn::Conv2d(torch::nn::Conv2dOptions(widths_.back(), channels_, 3).padding(1)));
}

torch::Tensor EncodePose(const torch::Tensor& pose, int bands) {
  if (bands <= 0) return pose;
  std::vector<torch::Tensor> parts{pose};
  for (int k = 0; k < bands; ++k) {
    const auto a = pose * (M_PI * std::pow(2.0, k));
    parts.push_back(torch::sin(a));
    parts.push_back(torch::cos(a));
  }
  return torch::cat(parts, 1);
}

torch::Tensor GeneratorImpl::forward(const torch::Tensor& pose) {
  auto x = torch::relu(fc1->forward(EncodePose(pose, fourier_bands_)));
  // PixelNorm: each pixel's feature vector to unit RMS (per sample; no batch statistics).
  const auto norm = [this](const torch::Tensor& t) {
    return pixel_norm_ ? t * torch::rsqrt(t.pow(2).mean(1, /*keepdim=*/true) + 1e-8) : t;
  };
  x = norm(torch::relu(fc2->forward(x)).reshape({pose.size(0), widths_[0], 4, 4}));
  for (size_t i = 0; i < convs->size(); ++i) {
    if (i > 0)
      x = torch::nn::functional::interpolate(
          x, torch::nn::functional::InterpolateFuncOptions()
                 .scale_factor(std::vector<double>{2.0, 2.0})
                 .mode(torch::kNearest));
    x = norm(torch::leaky_relu(convs[i]->as<torch::nn::Conv2d>()->forward(x), 0.2));
  }
  return torch::tanh(to_image->forward(x));
}

double GeneratorImpl::MacsPerView() const {
  double macs = static_cast<double>(fc1->options.in_features()) * fc1->options.out_features() +
                static_cast<double>(fc1->options.out_features()) * fc2->options.out_features();
  for (size_t i = 0; i < widths_.size(); ++i) {
    const double side = 4.0 * std::pow(2.0, static_cast<double>(i));
    const double cin = i == 0 ? widths_[0] : widths_[i - 1];
    macs += 9.0 * cin * widths_[i] * side * side;
  }
  const double side = 4.0 * std::pow(2.0, static_cast<double>(widths_.size() - 1));
  macs += 9.0 * widths_.back() * channels_ * side * side;
  return macs;
}

DiscriminatorImpl::DiscriminatorImpl(const P2iConfig& config) {
  const bool sn = config.spectral_norm;
  blocks = register_module("blocks", torch::nn::ModuleList());
  attentions = register_module("attentions", torch::nn::ModuleList());
  const int n_blocks = Log2(config.resolution) - 2;  // down to 4x4
  int cin = config.Channels();
  int width = config.d_base_width;
  int side = config.resolution;
  for (int i = 0; i < n_blocks; ++i) {
    blocks->push_back(SNConv2d(cin, width, 4, 2, 1, sn));
    side /= 2;
    // Self-attention costs (side^2)^2 per image: keep it to the coarser maps.
    const bool on = config.attention && side <= config.attention_max_res;
    attention_index_.push_back(on ? static_cast<int>(attentions->size()) : -1);
    if (on) attentions->push_back(SelfAttention(width, sn));
    cin = width;
    width = std::min(width * 2, config.d_max_width);
  }
  last = register_module("last", SNConv2d(cin, config.latent_dim, 3, 1, 1, sn));
  md = register_module("md", SNLinear(config.latent_dim, 1, sn));
  const bool sn_map = sn && config.sn_mappings;
  mp1 = register_module("mp1", SNLinear(7, config.mapping_width, sn_map));
  mp2 = register_module("mp2", SNLinear(config.mapping_width, config.latent_dim, sn_map));
  ml1 = register_module("ml1", SNLinear(config.latent_dim, config.mapping_width, sn_map));
  ml2 = register_module("ml2", SNLinear(config.mapping_width, 7, sn_map));
}

DOutput DiscriminatorImpl::forward(const torch::Tensor& image) {
  auto x = image;
  for (size_t i = 0; i < blocks->size(); ++i) {
    x = torch::leaky_relu(blocks[i]->as<SNConv2d>()->forward(x), 0.2);
    if (attention_index_[i] >= 0)
      x = attentions[attention_index_[i]]->as<SelfAttention>()->forward(x);
  }
  x = torch::leaky_relu(last->forward(x), 0.2);
  DOutput out;
  out.latent = x.sum({2, 3});
  out.score = md->forward(out.latent).squeeze(1);
  out.pose = ml2->forward(torch::leaky_relu(ml1->forward(out.latent), 0.2));
  return out;
}

torch::Tensor DiscriminatorImpl::MapPose(const torch::Tensor& pose) {
  return mp2->forward(torch::leaky_relu(mp1->forward(pose), 0.2));
}

EnhancerImpl::EnhancerImpl(const P2iConfig& config)
    : channels_(config.Channels()),
      width_(config.enet_width),
      blocks_(config.enet_blocks),
      res_(config.resolution) {
  head = register_module(
      "head", torch::nn::Conv2d(torch::nn::Conv2dOptions(channels_, width_, 3).padding(1)));
  body = register_module("body", torch::nn::ModuleList());
  for (int i = 0; i < 2 * blocks_; ++i)
    body->push_back(torch::nn::Conv2d(torch::nn::Conv2dOptions(width_, width_, 3).padding(1)));
  tail = register_module(
      "tail", torch::nn::Conv2d(torch::nn::Conv2dOptions(width_, channels_, 3).padding(1)));
  // Start as the identity map so phase 2 begins from G's output.
  torch::NoGradGuard no_grad;
  tail->weight.zero_();
  tail->bias.zero_();
}

torch::Tensor EnhancerImpl::forward(const torch::Tensor& image) {
  auto x = torch::relu(head->forward(image));
  for (int i = 0; i < blocks_; ++i) {
    auto y = torch::relu(body[2 * i]->as<torch::nn::Conv2d>()->forward(x));
    y = body[2 * i + 1]->as<torch::nn::Conv2d>()->forward(y);
    x = torch::relu(x + y);
  }
  return image + tail->forward(x);
}

double EnhancerImpl::MacsPerView() const {
  const double px = static_cast<double>(res_) * res_;
  return 9.0 * px * (2.0 * channels_ * width_ + 2.0 * blocks_ * width_ * width_);
}

int64_t CountParameters(const torch::nn::Module& module) {
  int64_t n = 0;
  for (const auto& p : module.parameters()) n += p.numel();
  return n;
}

FrozenScope::FrozenScope(torch::nn::Module& module) {
  for (auto& p : module.parameters()) {
    if (!p.requires_grad()) continue;
    p.requires_grad_(false);
    frozen_.push_back(p);
  }
}

FrozenScope::~FrozenScope() {
  for (auto& p : frozen_) p.requires_grad_(true);
}

}  // namespace p2i::model
