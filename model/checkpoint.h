/// @file checkpoint.h
/// @brief Model checkpoints: one file holding the modules, the optimiser states, the CPU RNG
/// state and a JSON metadata record (format version, config, pose normalisation, resolution,
/// channels, steps, camera). Written atomically. An *inference* checkpoint (ExportInference in
/// export.h) holds only the metadata, G and ENET. INTERNAL to model/ (includes LibTorch).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include <torch/torch.h>

#include "model/networks.h"
#include "model/p2i_config.h"
#include "scene/camera_info.h"

namespace p2i::model {

/// Bumped whenever the file layout or a module's parameter layout changes. Loading a checkpoint
/// of another version is refused.
constexpr int kCheckpointFormatVersion = 2;

/// The checkpoint's metadata (stored as JSON inside the file).
struct CheckpointMeta {
  int format_version = kCheckpointFormatVersion;
  P2iConfig config;
  PoseNormalizer normalizer;
  scene::CameraInfo camera;  ///< intrinsics of the views at config.resolution
  int phase1_step = 0;       ///< phase-1 steps done
  int phase2_step = 0;       ///< phase-2 (ENET) steps done
  double lr_scale = 1.0;     ///< divergence-guard learning-rate factor
  int rollbacks = 0;
  /// An exported inference checkpoint: meta, G and ENET only (no D, optimisers or RNG state).
  /// Stored as "kind": "inference" ("full" otherwise; files without the key are full).
  bool inference_only = false;

  std::string ToJson() const;
  static CheckpointMeta FromJson(const std::string& json, const std::string& source);
};

/// The networks of one model. d and e are null for the CNN baseline (e also when enet is off).
struct Networks {
  /// with_discriminator = false leaves d null (rendering needs only G and ENET).
  explicit Networks(const P2iConfig& config, bool with_discriminator = true);
  Generator g{nullptr};
  Discriminator d{nullptr};
  Enhancer e{nullptr};
  /// The moving average of G (config.g_ema > 0, P2I-NET only), starting as a copy of g.
  Generator g_ema{nullptr};
  /// The G that renders: g_ema when present, else g.
  Generator& Serving() { return g_ema ? g_ema : g; }
};

/// Optimisers to save/restore with a checkpoint (any may be null).
struct Optimizers {
  torch::optim::Adam* g = nullptr;
  torch::optim::Adam* d = nullptr;
  torch::optim::Adam* e = nullptr;
};

/// Calls writer(temp_path), then renames the temp file onto `path`. If writer throws, the temp
/// file is removed, `path` is left as it was and the exception propagates.
void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string& temp_path)>& writer);

/// Writes everything atomically. Throws std::runtime_error naming the path on failure. With
/// meta.inference_only only G and ENET are written (no D, optimisers or RNG state).
void SaveCheckpoint(const std::string& path, const CheckpointMeta& meta, Networks& nets,
                    const Optimizers& optimizers);

/// Reads only the metadata. Throws std::runtime_error if the file is missing, unreadable or of
/// another format version (the message says which version and what to do).
CheckpointMeta ReadCheckpointMeta(const std::string& path);

/// Loads modules (and optimisers / RNG state when given / asked) into already-constructed
/// networks built from the checkpoint's config. Returns the metadata. Refuses an inference
/// checkpoint (it has no D / optimiser state to resume from; use LoadWeights).
CheckpointMeta LoadCheckpoint(const std::string& path, Networks& nets,
                              const Optimizers& optimizers, bool restore_rng);

/// Loads only G (and G_EMA into nets.g_ema when set: from the file's G_EMA, else a copy of G)
/// and ENET (when `nets.e` is set and with_enet) from a full or an inference checkpoint into
/// networks of the same shape; D, optimisers and the RNG are untouched. Returns the metadata.
CheckpointMeta LoadWeights(const std::string& path, Networks& nets, bool with_enet = true);

/// For rendering: loads the G that serves (the file's G_EMA when it has one, else G) into
/// nets.g, and ENET when nets.e is set.
CheckpointMeta LoadServingWeights(const std::string& path, Networks& nets);

/// Copies a's parameters and buffers into b (same shape), without autograd.
void CopyWeights(torch::nn::Module& from, torch::nn::Module& to);

}  // namespace p2i::model
