/// @file sim_sensor_options.h
/// @brief Optional sensor effects of the synthetic camera (noise, depth holes): all off by default.
#pragma once

#include <cstdint>
#include <string>

namespace YAML {
class Node;
}

namespace p2i::scene {

/// What the simulated sensor does to ideal renders. Every effect is off at its default value, so
/// a default-constructed struct gives the exact rendering. Random effects are seeded: the same
/// seed, pose and camera give the same pixels. A value type: thread-compatible.
struct SimSensorOptions {
  double rgb_noise_sigma = 0.0;        ///< Gaussian noise on each 8-bit channel (grey levels)
  double depth_noise_sigma = 0.0;      ///< Gaussian depth noise sigma (m) = a + b * z^2 with
  double depth_noise_quadratic = 0.0;  ///< a = depth_noise_sigma, b = depth_noise_quadratic
  double min_range = 0.0;              ///< depth below this is invalid (0 = no limit)
  double max_range = 0.0;              ///< depth beyond this is invalid (0 = no limit)
  double grazing_angle_deg = 0.0;      ///< holes where the view ray meets the surface at an
                                       ///< incidence angle above this (0 = off), like a Kinect
  double depth_dropout = 0.0;          ///< probability that a valid depth pixel is dropped
  std::uint32_t seed = 0;

  /// Roughly a Kinect v1: 0.5-4.5 m range, quadratic depth noise, holes beyond 75 degrees.
  static SimSensorOptions Kinect(std::uint32_t seed = 0);

  /// Keys: preset (none|kinect, applied first), rgb_noise_sigma, depth_noise_sigma,
  /// depth_noise_quadratic, min_range, max_range, grazing_angle_deg, depth_dropout, seed.
  /// Throws std::runtime_error naming `source` and the key on an unknown key or a bad value.
  static SimSensorOptions FromYaml(const YAML::Node& node, const std::string& source);

  /// Throws std::invalid_argument on negative or non-finite values or dropout outside [0, 1].
  void Validate() const;

  bool AnyEnabled() const;
};

}  // namespace p2i::scene
