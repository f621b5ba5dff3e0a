/// @file method_loader.h
/// @brief The real SynthesizerLoader (P2I-NET / CNN checkpoints, nearest keyframe, depth warp)
/// and the training data the baselines and the coverage score need.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nodes/synthesizer/synthesizer_core.h"
#include "scene/camera_info.h"
#include "scene/rgbd_sample.h"

namespace p2i::nodes {

/// The camera of the built-in training data at width x height: Kinect-like 58 degree
/// horizontal field of view, f = 525 * width / 640, principal point at the centre (the same
/// camera `p2i render` and the sim camera node use).
scene::CameraInfo BuiltinCamera(int width, int height);

/// Training data from a spec:
///   ""                  -> empty dataset (no baseline frames, no coverage)
///   "builtin:NAME"      -> the built-in SimScene NAME rendered along the default arm sweep
///                          (scene::ArmSweepOptions defaults) at width x height
///   any other string    -> a dataset folder opened with scene::OpenDataset (capture, TUM,
///                          7-Scenes), centre-cropped and resized to width x height when both > 0
/// Every `stride`-th frame is kept. With `with_frames` false only poses and the camera are
/// filled (frames have empty images): enough for the coverage score, and cheap.
/// Throws std::runtime_error / std::invalid_argument naming the spec on failure.
scene::RgbdDataset LoadTrainingData(const std::string& spec, int width, int height,
                                    bool with_frames, int stride = 1);

struct LoaderOptions {
  int threads = 2;           ///< torch threads of learned methods (process-wide)
  int warp_k = 4;            ///< warp: source frames per view
  bool warp_fill_holes = true;
};

/// A loader for `method`: p2i and cnn load spec.checkpoint_path with model::LoadSynthesizer
/// (the checkpoint says which network it holds); nearest and warp build the baseline over
/// `training` (which must have frames) and ignore the checkpoint. Throws std::invalid_argument
/// for an unknown method or a baseline without training frames.
SynthesizerLoader MakeLoader(const std::string& method, const LoaderOptions& options,
                             std::shared_ptr<const scene::RgbdDataset> training);

}  // namespace p2i::nodes
