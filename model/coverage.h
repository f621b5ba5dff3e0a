/// @file coverage.h
/// @brief How far a pose lies from the training poses: a combined translation + rotation
/// distance, the nearest training pose(s), and a [0, 1] coverage score (1 = on the training
/// trajectory) that a robot can threshold to refuse views that will be wrong.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "scene/pose.h"

namespace YAML {
class Node;
}  // namespace YAML

namespace p2i::model {

/// d(a, b) = |t_a - t_b| (m) + metres_per_degree * angle(R_a^T R_b) (deg). A metre-valued
/// distance in which `metres_per_degree` says how many metres of travel one degree of rotation is
/// worth (default 0.01: 10 degrees ~ 10 cm).
double CombinedPoseDistance(const scene::Pose& a, const scene::Pose& b, double metres_per_degree);

/// Indices of the k poses of `poses` closest to `query` by CombinedPoseDistance, nearest first
/// (ties keep the lower index). Brute force: O(n log k) per query, fine for the few thousand
/// frames of a training set. Returns min(k, n) indices.
std::vector<size_t> NearestPoseIndices(const std::vector<scene::Pose>& poses,
                                       const scene::Pose& query, size_t k,
                                       double metres_per_degree);

struct CoverageOptions {
  double metres_per_degree = 0.01;  ///< rotation weight of CombinedPoseDistance
  /// Length scale of the score in units of the training spacing: score = exp(-(d / (falloff *
  /// spacing))^2). With 2: 0.78 one spacing away, 0.37 at two, 0.02 at four.
  double falloff = 2.0;
  /// Spacing used when it cannot be measured (a single training pose, or all poses identical), m.
  double fallback_spacing_m = 0.05;
  /// Reads the keys present in a YAML map (others keep their defaults), then Validate().
  /// Unknown keys and bad values throw std::runtime_error naming `source`, the line and the key.
  static CoverageOptions FromYaml(const YAML::Node& node, const std::string& source);
  /// Throws std::invalid_argument naming the field when a value is not positive and finite.
  void Validate() const;
};

/// Coverage score of poses against a fixed training set.
///
///   d_min(p)  = min_i CombinedPoseDistance(p, train_i)
///   spacing   = median over i of min_{j != i} CombinedPoseDistance(train_i, train_j)
///               (the typical step between neighbouring training poses; fallback when 0 or n<2)
///   score(p)  = exp(-(d_min(p) / (falloff * spacing))^2)          in (0, 1]
///
/// score is exactly 1 at a training pose and strictly decreases as d_min grows. Construction is
/// O(n^2) (spacing), each query O(n). Immutable after construction: const methods are safe to
/// call from several threads.
class CoverageScorer {
 public:
  /// Throws std::invalid_argument when `training_poses` is empty or the options are invalid.
  explicit CoverageScorer(std::vector<scene::Pose> training_poses, CoverageOptions options = {});

  double Score(const scene::Pose& pose) const;
  double NearestDistance(const scene::Pose& pose) const;
  /// The spacing in metres-equivalent (see the class comment).
  double spacing() const { return spacing_; }
  const CoverageOptions& options() const { return options_; }

 private:
  std::vector<scene::Pose> poses_;
  CoverageOptions options_;
  double spacing_ = 0.0;
};

}  // namespace p2i::model
