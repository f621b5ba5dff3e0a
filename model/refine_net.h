/// @file refine_net.h
/// @brief The `fusion` method's learned refinement: a small U-Net that takes the fused view's
/// inputs (candidate colours, confidences, raycast depth, normals, view rays; model/refine_input.h)
/// and outputs RGB-D as a residual on the plain blend, its loss, and its file. INTERNAL to model/
/// (includes LibTorch).
///
/// Grouped in one header and one .cc on purpose: every LibTorch translation unit costs about a
/// minute to compile on the project's machines.
#pragma once

#include <string>

#include <torch/torch.h>

#include "model/refine_options.h"

namespace p2i::model {

/// conv3x3 + ReLU, twice.
class RefineBlockImpl : public torch::nn::Module {
 public:
  RefineBlockImpl(int in, int out);
  torch::Tensor forward(const torch::Tensor& x);
  torch::nn::Conv2d a{nullptr}, b{nullptr};
};
TORCH_MODULE(RefineBlock);

/// U-Net: levels of RefineBlock with 2x2 average-pool down and bilinear-up + skip concat, then a
/// 3x3 head to 4 channels (RGB residual, depth residual) that starts at exactly zero, so an
/// untrained net returns the blend unchanged:
///
///   rgb   = clamp(base_rgb + head[0:3], 0, 1)                      (RGB in [0, 1])
///   depth = relu(base_depth + depth_residual_m * head[3])          (metres, 0 = invalid)
///
/// Input: batch x in_channels x H x W (any H, W: padded by replication to the level multiple
/// and cropped back). base: batch x 4 x H x W (blend RGB in [0, 1], depth in m). Not thread-safe
/// (a torch module); inference under torch::NoGradGuard is safe on one thread at a time.
class RefineUNetImpl : public torch::nn::Module {
 public:
  explicit RefineUNetImpl(const RefineNetOptions& options);
  /// Returns batch x 4 x H x W (rgb, depth) as above.
  torch::Tensor forward(const torch::Tensor& input, const torch::Tensor& base);
  /// Multiply-accumulates per pixel of one view (for FLOP figures).
  double MacsPerPixel() const;
  const RefineNetOptions& options() const { return options_; }

  torch::nn::ModuleList down, up;
  torch::nn::Conv2d head{nullptr};

 private:
  RefineNetOptions options_;
};
TORCH_MODULE(RefineUNet);

/// The leave-one-out loss over pixels where `target_valid` (batch x 1 x H x W, 0/1) is set for
/// RGB (all pixels of a real frame) and where the target depth is > 0 for depth.
struct RefineLossTerms {
  torch::Tensor total;  ///< (1 - w) l1_rgb + w dssim + depth_weight l1_depth
  torch::Tensor l1_rgb;
  torch::Tensor dssim;  ///< (1 - SSIM) / 2, 3x3 windows (as Monodepth2)
  torch::Tensor l1_depth;
};
/// out, target: batch x 4 x H x W (rgb in [0, 1], depth in m).
RefineLossTerms RefineLoss(const torch::Tensor& out, const torch::Tensor& target,
                           const RefineTrainOptions& options);

/// Metadata of a refinement file.
struct RefineFileMeta {
  int format_version = 1;
  RefineNetOptions net;
  std::string layout;          ///< the input layout name (RefineInputLayout::Name())
  int64_t steps = 0;           ///< optimiser steps the weights have seen in total
  std::string trained_on;      ///< free text: scenes / data that trained it
  std::string ToJson() const;
  static RefineFileMeta FromJson(const std::string& json, const std::string& source);
};

/// Writes meta + weights (+ Adam state when `optimizer` is given) atomically (tmp + rename).
/// Throws std::runtime_error naming the file.
void SaveRefineNet(const std::string& path, const RefineFileMeta& meta, RefineUNet& net,
                   torch::optim::Adam* optimizer = nullptr);
/// Reads the metadata only. Throws std::runtime_error naming the file when it is missing, not a
/// refinement file or of another format version.
RefineFileMeta ReadRefineMeta(const std::string& path);
/// Builds the net from the file's options and loads its weights. Throws std::runtime_error
/// naming the file.
RefineUNet LoadRefineNet(const std::string& path, RefineFileMeta* meta = nullptr);
/// Loads the Adam state saved with the weights into `optimizer` (built over the loaded net's
/// parameters); false when the file has none (a fresh optimiser is then fine).
bool LoadRefineOptimizer(const std::string& path, torch::optim::Adam& optimizer);

}  // namespace p2i::model
