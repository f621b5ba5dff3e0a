/// @file sim_texture.h
/// @brief Procedural textures of the synthetic scene: albedo from surface coordinates in metres.
#pragma once

#include <cstdint>

#include "scene/sim_scene_description.h"

namespace p2i::scene {

/// A material compiled for the inner shading loop (floats, precomputed reciprocals). Evaluation
/// is a pure function of (u, v): deterministic and thread-safe.
class SimTextureSampler {
 public:
  SimTextureSampler() = default;
  explicit SimTextureSampler(const SimMaterial& material);

  /// Albedo (linear RGB in [0, 1]) at surface coordinates (u, v) in metres.
  void Sample(float u, float v, float rgb[3]) const;

 private:
  SimTexture texture_ = SimTexture::kSolid;
  float c1_[3] = {0.7f, 0.7f, 0.7f};
  float c2_[3] = {0.3f, 0.3f, 0.3f};
  float inv_scale_ = 4.0f;
  std::uint32_t seed_ = 0;
};

}  // namespace p2i::scene
