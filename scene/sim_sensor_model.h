/// @file sim_sensor_model.h
/// @brief The simulated sensor's per-frame steps after rendering (internal to SimScene): colour
/// gains (auto-exposure, exposure and white-balance drift), 8-bit quantisation, per-pixel noise.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "scene/pose.h"
#include "scene/rgbd_sample.h"
#include "scene/sim_sensor_options.h"

namespace p2i::scene {

/// The key of a frame's noise: a hash of the seed, the stamp (when `stamped`), the exact pose
/// and the image size. Same inputs, same noise; different poses, independent noise.
std::uint64_t SensorNoiseKey(std::uint32_t seed, const Pose& camera_to_world, int w, int h,
                             double stamp, bool stamped);

/// A smooth signal of time in [-1, 1] (two sines, periods `period_s` and 0.37 `period_s`, phases
/// from `seed` and `channel`): the shape of every drift.
double SensorDrift(std::uint32_t seed, int channel, double stamp, double period_s);

/// Per-channel gains of the colour pipeline for a frame whose linear RGB (8-bit units, 3 per
/// pixel) is `linear_rgb`, captured at `stamp`: exposure (auto-exposure towards
/// exposure_target x (1 + exposure_drift x drift)) times white balance (red and blue
/// 1 + white_balance_drift x drift, green 1). All 1 when the colour effects are off.
std::array<float, 3> SensorColourGains(const SimSensorOptions& sensor,
                                       const std::vector<float>& linear_rgb, double stamp);

/// The mean Rec. 709 luminance of linear RGB in 8-bit units, divided by 255.
double MeanLuminance(const std::vector<float>& linear_rgb);

/// rgb = round(clamp(linear x gain)) as CV_8UC3 of w x h.
void QuantizeRgb(const std::vector<float>& linear_rgb, int w, int h,
                 const std::array<float, 3>& gains, cv::Mat* rgb);

/// Depth range, grazing-angle holes (`incidence_cos`: |cos| per pixel), dropout, depth noise and
/// RGB noise, in place, from counter-based randomness keyed by `key`.
void ApplySensorNoise(const SimSensorOptions& sensor, std::uint64_t key,
                      const std::vector<float>& incidence_cos, RgbdSample* out);

}  // namespace p2i::scene
