/// @file dataset_trajectories.h
/// @brief One string names the trajectories to render or publish: a generator, a generator YAML
/// file or inline map, or a TUM trajectory file (used by `p2i render`, pose_source and camera).
#pragma once

#include <string>
#include <vector>

#include "scene/pose.h"

namespace p2i::scene {

class SimScene;

/// Resolves `spec` to one or more trajectories:
///   - "arm_sweep", "adjacent_sweeps", "orbit", "random_walk": that generator with its defaults;
///   - an inline YAML flow map, e.g. "{type: orbit, radius: 1.2}" (see GenerateTrajectoriesFromYaml);
///   - a path ending in .yaml / .yml: a file holding such a map;
///   - any other path: a TUM trajectory file.
/// adjacent_sweeps gives several trajectories, the others one. random_walk needs `scene`.
/// Throws std::runtime_error naming the spec and what was expected.
std::vector<std::vector<StampedPose>> ResolveTrajectorySpec(const std::string& spec,
                                                            const SimScene* scene);

/// Replaces the stamps by start + i / rate (the paper's videos are 20 frames/s).
void Restamp(std::vector<StampedPose>* trajectory, double rate_hz, double start = 0.0);

}  // namespace p2i::scene
