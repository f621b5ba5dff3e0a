/// @file losses.cc
/// @brief P2I-NET losses (see losses.h).
#include "model/losses.h"

namespace p2i::model {

namespace {

// Per-sample Euclidean norm of a batch (flattened), mean over the batch.
torch::Tensor PerSampleNorm(const torch::Tensor& x) {
  return x.reshape({x.size(0), -1}).norm(2, 1);
}

}  // namespace

torch::Tensor ProjectionScore(const DOutput& d, const torch::Tensor& mapped_pose,
                              const LossWeights& w) {
  auto score = d.score;
  if (w.hd) {
    score = score + w.k1 * torch::cosine_similarity(d.latent, mapped_pose, 1, 1e-8);
  }
  return score;
}

DiscriminatorLossTerms DiscriminatorLoss(const DOutput& real, const DOutput& fake,
                                         const torch::Tensor& mapped_pose,
                                         const torch::Tensor& pose, const LossWeights& w) {
  DiscriminatorLossTerms t;
  const auto score_real = ProjectionScore(real, mapped_pose, w);
  const auto score_fake = ProjectionScore(fake, mapped_pose, w);
  t.pro = torch::relu(1.0 - score_real).mean() + torch::relu(1.0 + score_fake).mean();
  t.pe_real = PerSampleNorm(real.pose - pose).mean();
  // The tolerance is a constant: no gradient flows through gamma.
  t.gamma = ((real.score - fake.score).abs() * PerSampleNorm(real.pose)).detach();
  t.pe_fake = torch::relu(PerSampleNorm(fake.pose - real.pose) - t.gamma).mean();
  t.total = t.pro;
  if (w.ld) t.total = t.total + w.k2 * (t.pe_real + t.pe_fake);
  return t;
}

GeneratorLossTerms GeneratorLoss(const DOutput& fake, const torch::Tensor& mapped_pose,
                                 const torch::Tensor& pose, const LossWeights& w) {
  GeneratorLossTerms t;
  t.adv = -ProjectionScore(fake, mapped_pose, w).mean();
  t.pose = PerSampleNorm(fake.pose - pose).mean();
  t.total = w.ld ? t.adv + t.pose : t.adv;
  return t;
}

torch::Tensor Roberts(const torch::Tensor& image) {
  using torch::indexing::Slice;
  const auto a = image.index({Slice(), Slice(), Slice(0, -1), Slice(0, -1)});
  const auto b = image.index({Slice(), Slice(), Slice(1, torch::indexing::None),
                              Slice(1, torch::indexing::None)});
  const auto c = image.index({Slice(), Slice(), Slice(0, -1), Slice(1, torch::indexing::None)});
  const auto d = image.index({Slice(), Slice(), Slice(1, torch::indexing::None), Slice(0, -1)});
  return torch::cat({a - b, c - d}, 1);
}

EnetLossTerms EnetLoss(const torch::Tensor& enhanced, const torch::Tensor& real,
                       const LossWeights& w) {
  EnetLossTerms t;
  t.pixel = PerSampleNorm(enhanced - real).mean();
  t.edge = PerSampleNorm(Roberts(enhanced) - Roberts(real)).mean();
  t.total = t.pixel + w.k3 * t.edge;
  return t;
}

torch::Tensor ReconstructionLoss(const torch::Tensor& generated, const torch::Tensor& real) {
  return (generated - real).abs().mean();
}

torch::Tensor R1Penalty(const torch::Tensor& score_real, const torch::Tensor& real_images,
                        double gamma) {
  const auto grad = torch::autograd::grad({score_real.sum()}, {real_images}, {},
                                          /*retain_graph=*/true, /*create_graph=*/true)[0];
  return 0.5 * gamma * grad.pow(2).reshape({grad.size(0), -1}).sum(1).mean();
}

torch::Tensor RegressionLoss(const torch::Tensor& generated, const torch::Tensor& real) {
  return (generated - real).pow(2).mean();
}

}  // namespace p2i::model
