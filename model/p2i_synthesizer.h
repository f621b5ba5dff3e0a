/// @file p2i_synthesizer.h
/// @brief ViewSynthesizer backed by a trained P2I-NET (G, or G + ENET) or CNN-baseline
/// checkpoint. Torch-free header (pimpl).
#pragma once

#include <memory>
#include <string>

#include "model/view_synthesizer.h"

namespace p2i::model {

/// How a checkpoint is run.
struct SynthesizerOptions {
  int threads = 2;           ///< torch::set_num_threads (process-wide in LibTorch)
  /// "auto": G + ENET when the checkpoint has a trained ENET (phase 2 steps > 0), else G;
  /// "g": G only; "g+enet": require ENET.
  std::string stage = "auto";
  /// Depth below this many metres (the network's "0 m" end plus noise) is reported invalid (0).
  double min_valid_depth = 0.05;
  void Validate() const;
};

/// Renders views from a checkpoint: eval mode, inference mode (no autograd), input buffer
/// preallocated. Not thread-safe (one caller at a time), like every ViewSynthesizer.
class P2iSynthesizer : public ViewSynthesizer {
 public:
  /// Throws std::runtime_error naming the checkpoint on a missing file, another format version
  /// or a stage the checkpoint cannot provide.
  P2iSynthesizer(const std::string& checkpoint_path, const SynthesizerOptions& options = {});
  ~P2iSynthesizer() override;

  std::string Name() const override;
  scene::CameraInfo Camera() const override;
  scene::RgbdSample Render(const scene::Pose& pose) override;
  std::vector<scene::RgbdSample> RenderBatch(const std::vector<scene::Pose>& poses) override;
  int64_t ParameterCount() const override;
  double FlopsPerView() const override;

  /// True when ENET runs after G.
  bool UsesEnet() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The factory nodes and tools use.
std::unique_ptr<ViewSynthesizer> LoadSynthesizer(const std::string& checkpoint_path,
                                                 const SynthesizerOptions& options = {});

}  // namespace p2i::model
