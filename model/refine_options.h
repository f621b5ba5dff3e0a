/// @file refine_options.h
/// @brief Shape and training options of the learned refinement U-Net of the `fusion` method
/// (model/refine_net.h). Torch-free: nodes and tools set these.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace p2i::model {

/// Shape of the refinement U-Net. `in_channels` is fixed by the input layout
/// (model/refine_input.h: RefineInputChannels); the widths say how big the net is.
struct RefineNetOptions {
  int in_channels = 0;               ///< filled from the input layout
  std::vector<int> widths{12, 24, 48};  ///< channels per U-Net level (full res, 1/2, 1/4, ...)
  /// Depth residual scale (m): the depth head's output is multiplied by it.
  double depth_residual_m = 0.25;
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
  /// The input must be a multiple of this in both sizes (the net pads to it otherwise).
  int Multiple() const { return 1 << (static_cast<int>(widths.size()) - 1); }
};

/// Leave-one-out training / fine-tuning of the refinement.
struct RefineTrainOptions {
  int steps = 200;            ///< optimiser steps of one Fit() call
  int batch_size = 4;
  double lr = 1e-3;
  double ssim_weight = 0.2;   ///< loss = (1 - w) L1(rgb) + w (1 - SSIM(rgb))/2 + depth_weight L1(depth)
  double depth_weight = 0.5;  ///< on depth in metres (pixels valid in the target only)
  int crop = 0;               ///< > 0: random square crops of this size (multiple of the net's)
  int threads = 1;            ///< torch::set_num_threads for the fit
  uint64_t seed = 1;
  void Validate() const;
};

}  // namespace p2i::model
