/// @file sim_sensor_options.h
/// @brief Optional effects of the simulated RGB-D sensor (depth noise and holes, auto-exposure,
/// white-balance drift, RGB noise, motion blur): all off by default.
#pragma once

#include <cstdint>
#include <string>

namespace YAML {
class Node;
}

namespace p2i::scene {

/// What the simulated sensor does to ideal renders. Every effect is off at its default value, so
/// a default-constructed struct gives the exact rendering. Random effects are seeded: the same
/// seed, pose, stamp and camera give the same pixels. A value type: thread-compatible.
///
/// Order of the colour pipeline: the linear image (averaged over the shutter time when motion
/// blur is on) is multiplied by the exposure gain (auto-exposure x drift) and the white-balance
/// gains, quantised to 8 bits, then RGB noise is added.
struct SimSensorOptions {
  // Depth.
  double depth_noise_sigma = 0.0;      ///< Gaussian depth noise sigma (m) = a + b * z^2 with
  double depth_noise_quadratic = 0.0;  ///< a = depth_noise_sigma, b = depth_noise_quadratic
  double min_range = 0.0;              ///< depth below this is invalid (0 = no limit)
  double max_range = 0.0;              ///< depth beyond this is invalid (0 = no limit)
  double grazing_angle_deg = 0.0;      ///< holes where the view ray meets the surface at an
                                       ///< incidence angle above this (0 = off), like a Kinect
  double depth_dropout = 0.0;          ///< probability that a valid depth pixel is dropped
  // Colour.
  double rgb_noise_sigma = 0.0;   ///< Gaussian noise on each 8-bit channel (grey levels)
  double auto_exposure = 0.0;     ///< strength in [0, 1]: gain = (target / mean luminance)^strength
                                  ///< of the frame itself (0 = fixed exposure, 1 = every frame
                                  ///< brought to the target), clamped to [1/4, 4]
  double exposure_target = 0.45;  ///< mean luminance in (0, 1] that auto-exposure aims for
  double exposure_drift = 0.0;    ///< relative amplitude of a slow, smooth gain drift in time
  double white_balance_drift = 0.0;  ///< relative amplitude of slow red and blue gain drifts
  double drift_period_s = 8.0;       ///< period (s) of the slowest drift component
  // Motion.
  double exposure_time_s = 0.0;  ///< shutter time: RGB averages the camera's motion over it (0 =
                                 ///< no blur; needs the shutter poses, see SimScene)
  int motion_blur_samples = 5;   ///< renders averaged over the shutter time
  // Pixel area.
  /// N: each pixel's colour is the mean of N x N rays spread evenly over its area, as a camera
  /// pixel integrates the light over its area (no aliasing of fine texture). Odd, 1 to 7; 1 = one
  /// ray through the pixel's centre (the exact render). Depth, holes and noise come from the
  /// centre ray either way.
  int pixel_samples = 1;
  std::uint32_t seed = 0;

  /// Roughly a Kinect v1: 0.5-4.5 m range, quadratic depth noise, holes beyond 75 degrees.
  static SimSensorOptions Kinect(std::uint32_t seed = 0);
  /// The bench's sensor model: Kinect depth plus auto-exposure (strength 0.6), exposure drift
  /// 8 %, white-balance drift 4 % and a 30 ms shutter (motion blur, 5 samples). One ray per
  /// pixel (pixel_samples 1), so that the figures of earlier bench runs stay reproducible: add
  /// `pixel_samples: 3` for pixels that integrate over their area (docs/SCENE.md).
  static SimSensorOptions Realistic(std::uint32_t seed = 0);
  /// The options of a preset by name: "none" (all off), "kinect" or "realistic". Throws
  /// std::invalid_argument naming the preset and the allowed names otherwise.
  static SimSensorOptions FromPreset(const std::string& preset, std::uint32_t seed = 0);
  /// True when `preset` names one of FromPreset's presets.
  static bool IsPreset(const std::string& preset);

  /// Keys: preset (none|kinect|realistic, applied first), then any field above by its name.
  /// Throws std::runtime_error naming `source`, the line and the key on an unknown key or a bad
  /// value.
  static SimSensorOptions FromYaml(const YAML::Node& node, const std::string& source);

  /// Throws std::invalid_argument naming the field and its value when it is out of range.
  void Validate() const;

  bool AnyEnabled() const { return AnyNoise() || AnyColour() || MotionBlur() || PixelArea(); }
  /// Depth effects or RGB noise (the per-pixel random pass).
  bool AnyNoise() const;
  /// Auto-exposure, exposure drift or white-balance drift (per-frame gains).
  bool AnyColour() const;
  bool MotionBlur() const { return exposure_time_s > 0.0 && motion_blur_samples > 1; }
  bool PixelArea() const { return pixel_samples > 1; }
};

}  // namespace p2i::scene
