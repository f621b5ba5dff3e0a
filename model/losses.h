/// @file losses.h
/// @brief P2I-NET's losses exactly as ../shared/design/P2I-NET.md gives them, on batches.
/// INTERNAL to model/ (includes LibTorch). Pure functions: thread-safe.
#pragma once

#include <torch/torch.h>

#include "model/networks.h"

namespace p2i::model {

/// The switches and weights the losses use (a slice of P2iConfig).
struct LossWeights {
  bool hd = true;
  bool ld = true;
  double k1 = 1.0;
  double k2 = 1.0;
  double k3 = 1.0;
  static LossWeights From(const P2iConfig& c) { return {c.hd, c.ld, c.k1, c.k2, c.k3}; }
};

/// D_pro(I, y) = M_d(F_l(I)) + k1 * cos(F_l(I), M_p(y)); the cosine term only with HD.
/// d: D's output on I; mapped_pose: M_p(y). Returns one score per sample.
torch::Tensor ProjectionScore(const DOutput& d, const torch::Tensor& mapped_pose,
                              const LossWeights& w);

struct DiscriminatorLossTerms {
  torch::Tensor total;     ///< L_D = L_pro + k2 (L_PE-Ir + L_PE-Ig)  (k2 term only with LD)
  torch::Tensor pro;       ///< hinge: E[relu(1 - D_pro(I_r))] + E[relu(1 + D_pro(I_g))]
  torch::Tensor pe_real;   ///< L_PE-Ir = E ||M_l(F_l(I_r)) - y||
  torch::Tensor pe_fake;   ///< L_PE-Ig = E max(||M_l(F_l(I_g)) - M_l(F_l(I_r))|| - gamma, 0)
  torch::Tensor gamma;     ///< per sample, detached: |M_d(F_l(I_r)) - M_d(F_l(I_g))| ||M_l(F_l(I_r))||
};

/// real/fake: D on I_r and on I_g(y) (I_g detached by the caller for the D step);
/// mapped_pose: M_p(y); pose: the normalised y (batch x 7).
DiscriminatorLossTerms DiscriminatorLoss(const DOutput& real, const DOutput& fake,
                                         const torch::Tensor& mapped_pose,
                                         const torch::Tensor& pose, const LossWeights& w);

struct GeneratorLossTerms {
  torch::Tensor total;  ///< L_G = -E[D_pro(I_g, y)] + E ||M_l(F_l(I_g)) - y||  (pose term with LD)
  torch::Tensor adv;
  torch::Tensor pose;
};
GeneratorLossTerms GeneratorLoss(const DOutput& fake, const torch::Tensor& mapped_pose,
                                 const torch::Tensor& pose, const LossWeights& w);

/// Roberts cross on every channel: batch x (2 C) x (H-1) x (W-1), the two diagonal differences.
torch::Tensor Roberts(const torch::Tensor& image);

struct EnetLossTerms {
  torch::Tensor total;  ///< E||I_e - I_r|| + k3 E||Roberts(I_e) - Roberts(I_r)||  (L2 per view)
  torch::Tensor pixel;
  torch::Tensor edge;
};
EnetLossTerms EnetLoss(const torch::Tensor& enhanced, const torch::Tensor& real,
                       const LossWeights& w);

/// pix2pix-style reconstruction term on G: mean |I_g - I_r| over all pixels and channels.
torch::Tensor ReconstructionLoss(const torch::Tensor& generated, const torch::Tensor& real);

/// R1 penalty: gamma / 2 * E_batch ||d score_real / d real_images||^2. `real_images` must have
/// required grad before D ran on them; the result keeps the graph (create_graph) so it trains D.
torch::Tensor R1Penalty(const torch::Tensor& score_real, const torch::Tensor& real_images,
                        double gamma);

/// The CNN baseline's plain L2 regression: mean squared error over all pixels and channels.
torch::Tensor RegressionLoss(const torch::Tensor& generated, const torch::Tensor& real);

}  // namespace p2i::model
