/// @file densify.h
/// @brief Geometry-densified training frames (P2iConfig::densify_*, docs/MODEL.md): the training
/// frames plus views rendered by a method built over them at poses near the trajectory. A
/// learned method trained on them sees targets off the captured path, where the training frames
/// alone leave it to interpolate. Torch-free; part of p2i_methods (it builds the renderer from
/// the method registry).
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "model/p2i_config.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"

namespace p2i::model {

/// `pose` moved by a translation of uniformly random length in [0, max_offset_m] along a
/// uniformly random direction, and turned by an angle uniform in [0, max_angle_deg] about a
/// uniformly random axis (in the camera frame).
scene::Pose NearbyPose(const scene::Pose& pose, double max_offset_m, double max_angle_deg,
                       std::mt19937_64& rng);

/// True when some frame of `frames` lies within `gap_m` of `pose` and within `gap_deg` of its
/// orientation (the angle of the relative rotation).
bool NearAnyFrame(const scene::Pose& pose, const std::vector<scene::RgbdSample>& frames,
                  double gap_m, double gap_deg);

/// The id prefix of the views DensifyTrainingFrames appends ("densify/NNNNNN").
inline constexpr const char* kDensifiedIdPrefix = "densify/";

/// True for a view DensifyTrainingFrames rendered, false for a captured frame.
inline bool IsDensified(const scene::RgbdSample& frame) {
  return frame.id.rfind(kDensifiedIdPrefix, 0) == 0;
}

/// What DensifyTrainingFrames added.
struct DensifyReport {
  int added = 0;          ///< rendered views appended
  int skipped = 0;        ///< candidate poses skipped: a training frame within the min gap
  double render_s = 0.0;  ///< building the renderer and rendering, seconds
};

/// One line for logs: "densified: N views of METHOD near the training poses (X s)", plus the
/// skipped candidates when the min gap is on; empty when nothing was added or skipped.
std::string DensifySummary(const DensifyReport& report, const P2iConfig& config);

/// `train` and, appended, round(config.densify_ratio x train.frames.size()) views of
/// config.densify_method (built over `train` with its default options, hole filling on where
/// the method has it) at NearbyPose of training poses drawn uniformly (seeded by config.seed:
/// the same config and frames give the same views, so a resumed run sees the same data). With
/// densify_min_gap_m > 0 the candidates near a training frame (densify_min_gap_m and
/// densify_min_gap_deg) are dropped, not replaced: the views are those of the gap-off run minus
/// those, so a dense capture gets fewer than a sparse one. Their
/// ids are "densify/NNNNNN"; depth 0 where the renderer has no geometry. densify_ratio 0
/// returns `train` unchanged. Throws std::invalid_argument when the method is unknown, learned
/// (only methods built from frames can densify) or renders at another size than the frames.
scene::RgbdDataset DensifyTrainingFrames(const scene::RgbdDataset& train, const P2iConfig& config,
                                         DensifyReport* report = nullptr);

}  // namespace p2i::model
