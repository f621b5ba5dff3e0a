/// @file builtin_dataset.h
/// @brief What `builtin:NAME` means as training data, in one place: `p2i train --data` and the
/// synthesizer node's `dataset` parameter both use it.
#pragma once

#include <string>

#include "scene/rgbd_sample.h"

namespace p2i::scene {

/// "builtin:" — the prefix of built-in sim scene specs (SimScene::FromSpec).
extern const char kBuiltinPrefix[];

/// True for "builtin:NAME".
bool IsBuiltinSpec(const std::string& spec);

struct BuiltinDatasetOptions {
  int width = 640;           ///< image size of the rendered frames (> 0)
  int height = 480;
  int stride = 1;            ///< keep every stride-th pose of the sweep (>= 1)
  int max_frames = 0;        ///< after the stride, at most this many, evenly spaced (0 = all)
  bool with_frames = true;   ///< false: poses, stamps, ids and the camera only (cheap)
  /// Throws std::invalid_argument naming the bad value.
  void Validate() const;
};

/// `builtin:NAME` as training data: the built-in SimScene NAME rendered along the default arm
/// sweep (ArmSweepOptions{}: three arcs at 1.0, 1.3 and 1.6 m, 20 poses/s, ~500 poses; the
/// demo's measured trajectory) through the sim camera (SimScene::DefaultCamera(640, 480): f = 525
/// at 640 px, centred principal point) centre-cropped and resized to width x height
/// (CenterCropResizeCamera: what the camera node's frames become for the trainer and the
/// monitor's ground truth), rendered directly at that camera. Frame ids are "sweep/<pose index>". Exact
/// renders: no sensor noise. Throws std::invalid_argument for a spec without the prefix or bad
/// options, std::runtime_error (listing the names) for an unknown scene.
RgbdDataset RenderBuiltinDataset(const std::string& spec, const BuiltinDatasetOptions& options);

}  // namespace p2i::scene
