/// @file sim_scenes.h
/// @brief Training scenes for the cross-scene refinement network: the built-in sim rooms with
/// randomised materials (texture kind, colours, scale), lights (intensity, colour, ambient) and
/// sensor settings (RGB and depth noise, dropout, grazing-angle holes), each with a seeded random
/// walk. Torch-free.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "scene/rgbd_sample.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"

namespace p2i::refine {

struct SimScenesOptions {
  int scenes = 8;                 ///< variants (alternating over `bases`)
  std::vector<std::string> bases{"small_office", "large_office"};
  int frames = 40;                ///< frames per scene (every `frame_step`-th pose of the walk)
  int frame_step = 5;             ///< poses of the 20 Hz walk between kept frames
  int width = 128;                ///< rendered frame size
  int height = 96;
  uint64_t seed = 7;
  void Validate() const;
};

/// One randomised scene and its frames (rendered with its sensor model at the sim camera).
struct SimTrainingScene {
  std::string name;               ///< "<base>_v<i>"
  scene::RgbdDataset frames;
};

/// Deterministic for a given options value. Throws std::invalid_argument on bad options or an
/// unknown base scene.
std::vector<SimTrainingScene> MakeSimScenes(const SimScenesOptions& options);

/// The scene description of variant `index` (exposed for tests: materials and lights differ
/// from the base).
scene::SimScene MakeSimVariant(const std::string& base, int index, uint64_t seed);

}  // namespace p2i::refine
