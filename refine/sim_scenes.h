/// @file sim_scenes.h
/// @brief Training scenes for the cross-scene refinement network: the built-in sim rooms with
/// randomised materials (texture kind, colours, scale), lights (intensity, colour, ambient) and
/// sensor settings (RGB and depth noise, dropout, grazing-angle holes; optionally auto-exposure,
/// exposure and white-balance drift and motion blur), each with a seeded random walk, and
/// optionally recorded poses that carry the error of a real tracker. Torch-free.
#pragma once

#include <cstdint>
#include <random>
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
  /// Sensor model of the variants that have one (every third keeps the exact render):
  /// "kinect" (depth noise, holes, RGB noise) or "realistic" (kinect plus auto-exposure,
  /// exposure and white-balance drift and motion blur, SimSensorOptions::Realistic).
  std::string sensor = "kinect";
  /// Error of the recorded poses, as real capture has (SUN3D's are estimated): each frame is
  /// rendered at its true pose and recorded at the true pose perturbed by Gaussian translation
  /// (sigma up to pose_noise_m per axis) and rotation (sigma up to pose_noise_deg about a random
  /// axis); each scene draws its own scale of the two in [0, 1], so some scenes are nearly exact.
  /// The TSDF, the blend and the leave-one-out queries all see the recorded poses. 0 = exact.
  double pose_noise_m = 0.0;
  double pose_noise_deg = 0.0;
  /// Rays per pixel side of every variant's render (SimSensorOptions::pixel_samples: odd, 1-7):
  /// 3 = pixels that integrate over their area, as a real camera's (and the study-room frames)
  /// do; 1 = one ray per pixel, which aliases fine textures.
  int pixel_samples = 1;
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
scene::SimScene MakeSimVariant(const std::string& base, int index, uint64_t seed,
                               const std::string& sensor = "kinect", int pixel_samples = 1);

/// `pose` perturbed by Gaussian translation (sigma `sigma_m` per axis) and a rotation of Gaussian
/// angle (sigma `sigma_deg`) about a uniformly random axis. Exposed for tests.
scene::Pose PerturbPose(const scene::Pose& pose, double sigma_m, double sigma_deg,
                        std::mt19937_64& rng);

}  // namespace p2i::refine
