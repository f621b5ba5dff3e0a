/// @file refiner.h
/// @brief The refinement network behind a torch-free interface: refine one fused view, fit
/// (leave-one-out) on samples, evaluate, save and load. The trainer node, the synthesizer and the
/// tools use this; the LibTorch module is model/refine_net.h.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "model/refine_options.h"

namespace p2i::model {

/// What the network sees for one view: the plain blend (the residual's base) and the input
/// planes, float32 CHW (`channels` planes of the blend's size), in the order of the layout
/// (fusion/view_candidates.h PackRefinementInput; model/learned_refiner.h fills it).
struct RefineInput {
  cv::Mat base_rgb;              ///< CV_32FC3, RGB in [0, 1]
  cv::Mat base_depth;            ///< CV_32FC1, metres, 0 = none
  std::vector<float> planes;     ///< channels x rows x cols
  int channels = 0;
};

/// A leave-one-out training sample: the input of frame i rendered without frame i, and frame i.
struct RefineSample {
  RefineInput input;
  cv::Mat target_rgb;            ///< CV_8UC3 RGB
  cv::Mat target_depth;          ///< CV_32FC1 metres, 0 = invalid (not counted)
};

struct RefineFitReport {
  int steps = 0;                 ///< optimiser steps of this call
  int64_t total_steps = 0;       ///< steps the weights have seen
  double first_loss = 0.0;       ///< mean loss of the first min(10, steps) steps
  double last_loss = 0.0;        ///< mean loss of the last min(10, steps) steps
  bool stopped = false;          ///< should_stop ended the fit early
};

/// PSNR (dB) of the refined and of the plain blend against the targets of `samples`.
struct RefineEval {
  double psnr_refined = 0.0;
  double psnr_blend = 0.0;
  double ssim_refined = 0.0;
  double ssim_blend = 0.0;
  int views = 0;
};

/// Not thread-safe: one caller at a time (a torch module inside). Copyable by Clone().
class Refiner {
 public:
  /// A fresh net (identity on the blend). Throws std::invalid_argument on bad options.
  Refiner(const RefineNetOptions& net, const std::string& layout);
  /// From a refinement file (model/refine_net.h SaveRefineNet). Throws std::runtime_error
  /// naming the file; with `expected_layout` set, a file of another layout is refused.
  static std::unique_ptr<Refiner> Load(const std::string& path,
                                       const std::string& expected_layout = "");
  ~Refiner();
  std::unique_ptr<Refiner> Clone() const;

  /// Refines one view: rgb CV_8UC3 RGB, depth CV_32FC1 metres (0 = invalid).
  void Refine(const RefineInput& input, cv::Mat* rgb, cv::Mat* depth);
  /// Adam steps on random mini-batches of `samples` (all the same size unless options.crop).
  /// The optimiser state persists across calls. should_stop is polled between steps.
  RefineFitReport Fit(const std::vector<RefineSample>& samples, const RefineTrainOptions& options,
                      const std::function<bool()>& should_stop = {});
  RefineEval Evaluate(const std::vector<RefineSample>& samples);
  /// Atomic (tmp + rename); with_optimizer keeps the Adam state for resuming.
  void Save(const std::string& path, const std::string& trained_on, bool with_optimizer = false);

  const RefineNetOptions& net_options() const;
  const std::string& layout() const;
  int64_t total_steps() const;
  int64_t ParameterCount() const;
  double MacsPerPixel() const;

 private:
  Refiner();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace p2i::model
