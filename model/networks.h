/// @file networks.h
/// @brief P2I-NET's LibTorch modules: generator G, discriminator D (with F_l, M_d, M_p, M_l),
/// enhancement network ENET, spectral-normalised layers, SAGAN self-attention, pose
/// normalisation. INTERNAL to model/ (and tests/model): includes LibTorch.
///
/// These are grouped in one header on purpose: every LibTorch translation unit costs about a
/// minute to compile on the project's machines.
#pragma once

#include <array>
#include <vector>

#include <torch/torch.h>

#include "model/p2i_config.h"

namespace p2i::model {

/// Maps poses to the normalised 7-vector the networks see: translation to [-1, 1] per axis over
/// the training set's bounds (with a 5% margin), the unit quaternion with the sign that puts it
/// on q_ref's side (q and -q are the same rotation). A value type saved with every checkpoint.
///
/// Why q_ref: the canonical sign qw >= 0 (scene::Pose) flips the whole quaternion where qw
/// crosses 0, i.e. for rotations near 180 deg from the world frame. A capture that looks that
/// way (the study-room data: qw within 0.015 of 0, 11 of 50 frames flipped) would hand the
/// networks two far-apart inputs (distance ~2) for rotations a degree apart. Measured against
/// the training set's principal rotation instead, the sign flips only 180 deg away from it.
struct PoseNormalizer {
  std::array<double, 3> t_min{-1, -1, -1};
  std::array<double, 3> t_max{1, 1, 1};
  /// Reference rotation (qx qy qz qw). Identity = the plain qw >= 0 sign (checkpoints written
  /// before q_ref existed load with it, so they see the inputs they were trained on).
  std::array<double, 4> q_ref{0, 0, 0, 1};
  /// Bounds and principal rotation of `poses` (rows of 7: tx ty tz qx qy qz qw).
  static PoseNormalizer FromPoses(const std::vector<std::array<double, 7>>& poses);
  /// The principal rotation of `poses`: the unit quaternion q maximising sum_i (q . q_i)^2
  /// (the dominant eigenvector of sum_i q_i q_i^T, Markley et al. 2007), so the sign of each
  /// q_i does not matter; returned with qw >= 0. Identity for no poses.
  static std::array<double, 4> PrincipalRotation(const std::vector<std::array<double, 7>>& poses);
  std::array<float, 7> Normalize(const std::array<double, 7>& pose) const;
};

/// Linear layer with optional spectral normalisation (Miyato et al. 2018): the weight is divided
/// by its largest singular value, estimated by one power iteration per training-mode forward
/// (u persists as a buffer, as in PyTorch's torch.nn.utils.spectral_norm). Not thread-safe.
class SNLinearImpl : public torch::nn::Module {
 public:
  SNLinearImpl(int in, int out, bool sn);
  torch::Tensor forward(const torch::Tensor& x);
  /// The weight the forward pass uses (W / sigma when SN is on).
  torch::Tensor EffectiveWeight();
  torch::Tensor weight, bias, u;
  bool sn_;
};
TORCH_MODULE(SNLinear);

/// Conv2d with optional spectral normalisation (weight reshaped to out x (in*k*k)).
class SNConv2dImpl : public torch::nn::Module {
 public:
  SNConv2dImpl(int in, int out, int kernel, int stride, int padding, bool sn);
  torch::Tensor forward(const torch::Tensor& x);
  torch::Tensor EffectiveWeight();
  torch::Tensor weight, bias, u;
  int stride_, padding_;
  bool sn_;
};
TORCH_MODULE(SNConv2d);

/// SAGAN self-attention: out = x + gamma * softmax(f(x)^T g(x)) h(x), gamma starts at 0 so the
/// block begins as the identity.
class SelfAttentionImpl : public torch::nn::Module {
 public:
  SelfAttentionImpl(int channels, bool sn);
  torch::Tensor forward(const torch::Tensor& x);
  SNConv2d f{nullptr}, g{nullptr}, h{nullptr};
  torch::Tensor gamma;
};
TORCH_MODULE(SelfAttention);

/// G: normalised 7-d pose -> image in [-1, 1] (channels x res x res). A 2-layer MLP makes a 4x4
/// seed of widths[0] channels; each further stage is nearest x2 upsampling + 3x3 conv + ReLU;
/// a 3x3 conv to the output channels + tanh ends it.
class GeneratorImpl : public torch::nn::Module {
 public:
  explicit GeneratorImpl(const P2iConfig& config);
  torch::Tensor forward(const torch::Tensor& pose);
  /// Multiply-accumulates of one forward pass for one view.
  double MacsPerView() const;
  torch::nn::Linear fc1{nullptr}, fc2{nullptr};
  torch::nn::ModuleList convs;
  torch::nn::Conv2d to_image{nullptr};
  std::vector<int> widths_;
  int channels_;
  bool pixel_norm_;
  int fourier_bands_;  ///< 0 = the pose as is
};
TORCH_MODULE(Generator);

/// G's pose input: `pose` (batch x 7) as is for bands = 0, else with its Fourier features
/// [y, sin(2^k pi y), cos(2^k pi y)], k < bands (batch x 7 (1 + 2 bands)).
torch::Tensor EncodePose(const torch::Tensor& pose, int bands);

/// What D computes for one batch: the latent F_l and the mapped heads.
struct DOutput {
  torch::Tensor latent;    ///< F_l(I): batch x latent_dim
  torch::Tensor score;     ///< M_d(F_l(I)): batch
  torch::Tensor pose;      ///< M_l(F_l(I)): batch x 7
};

/// D: blocks of (SN conv 4x4 stride 2 + LeakyReLU 0.2 [+ self-attention]) down to 4x4, then a
/// SN 3x3 conv to latent_dim channels and global sum pooling: F_l. Heads M_d (latent -> 1),
/// M_p (pose -> latent), M_l (latent -> pose), SN'd.
class DiscriminatorImpl : public torch::nn::Module {
 public:
  explicit DiscriminatorImpl(const P2iConfig& config);
  DOutput forward(const torch::Tensor& image);
  torch::Tensor MapPose(const torch::Tensor& pose);  ///< M_p(y)
  torch::nn::ModuleList blocks;
  torch::nn::ModuleList attentions;  // only the active ones
  std::vector<int> attention_index_;  // per block: index into attentions, -1 = none
  SNConv2d last{nullptr};
  SNLinear md{nullptr}, mp1{nullptr}, mp2{nullptr}, ml1{nullptr}, ml2{nullptr};
};
TORCH_MODULE(Discriminator);

/// ENET: a plain residual CNN, I_e = I_g + conv(...(I_g)) (the renderer clamps to [-1, 1]).
class EnhancerImpl : public torch::nn::Module {
 public:
  EnhancerImpl(const P2iConfig& config);
  torch::Tensor forward(const torch::Tensor& image);
  double MacsPerView() const;
  torch::nn::Conv2d head{nullptr}, tail{nullptr};
  torch::nn::ModuleList body;
  int channels_, width_, blocks_, res_;
};
TORCH_MODULE(Enhancer);

int64_t CountParameters(const torch::nn::Module& module);

/// For its scope, the parameters of `module` do not require gradients (restored on exit): a
/// frozen network inside another network's step, e.g. D in G's step. Gradients still flow
/// *through* it to the trained network's output, unchanged; only its own weight gradients,
/// which that step would discard, are not computed.
class FrozenScope {
 public:
  explicit FrozenScope(torch::nn::Module& module);
  ~FrozenScope();
  FrozenScope(const FrozenScope&) = delete;
  FrozenScope& operator=(const FrozenScope&) = delete;

 private:
  std::vector<torch::Tensor> frozen_;
};

}  // namespace p2i::model
