/// @file sim_sensor_model.cc
/// @brief Colour gains, quantisation and counter-based sensor noise of the simulated camera.
#include "scene/sim_sensor_model.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace p2i::scene {
namespace {

std::uint64_t Mix64(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  x ^= x >> 31;
  return x;
}

/// A uniform number in [0, 1) from 16 bits.
inline float Uniform16(std::uint64_t bits) {
  return static_cast<float>(bits & 0xffffu) * (1.0f / 65536.0f);
}

/// An approximately standard-normal number from 64 random bits: the sum of four 16-bit
/// uniforms (Irwin-Hall), centred and scaled to unit variance. Tails end at +-3.46 sigma, which
/// is fine for sensor noise and much cheaper than std::normal_distribution.
inline float Gaussian4(std::uint64_t bits) {
  const float sum =
      Uniform16(bits) + Uniform16(bits >> 16) + Uniform16(bits >> 32) + Uniform16(bits >> 48);
  return (sum - 2.0f) * 1.7320508f;
}

inline std::uint8_t To8Bit(float c) {
  return static_cast<std::uint8_t>(c < 0.0f ? 0.0f : (c > 255.0f ? 255.0f : c));
}

// Auto-exposure never changes the gain by more than this factor either way.
constexpr double kMaxAutoGain = 4.0;

}  // namespace

std::uint64_t SensorNoiseKey(std::uint32_t seed, const Pose& camera_to_world, int w, int h,
                             double stamp, bool stamped) {
  std::uint64_t key = Mix64(seed + 0x1234567ull);
  if (stamped) {
    std::uint64_t bits;
    std::memcpy(&bits, &stamp, sizeof bits);
    key = Mix64(key ^ bits ^ 0x5851f42d4c957f2dull);
  }
  const Vector7d v7 = camera_to_world.ToVector7();
  for (int k = 0; k < 7; ++k) {
    std::uint64_t bits;
    std::memcpy(&bits, &v7[k], sizeof bits);
    key = Mix64(key ^ bits);
  }
  return Mix64(key ^ (static_cast<std::uint64_t>(w) << 32 | static_cast<std::uint64_t>(h)));
}

double SensorDrift(std::uint32_t seed, int channel, double stamp, double period_s) {
  const std::uint64_t h = Mix64(Mix64(seed + 0x2545f4914f6cdd1dull) + channel);
  const double phase1 = 2.0 * M_PI * static_cast<double>(h & 0xffffu) / 65536.0;
  const double phase2 = 2.0 * M_PI * static_cast<double>((h >> 16) & 0xffffu) / 65536.0;
  const double w = 2.0 * M_PI / period_s;
  return 0.6 * std::sin(w * stamp + phase1) + 0.4 * std::sin(w / 0.37 * stamp + phase2);
}

double MeanLuminance(const std::vector<float>& linear_rgb) {
  double sum = 0.0;
  const std::size_t n = linear_rgb.size() / 3;
  for (std::size_t i = 0; i < n; ++i) {
    const float* p = &linear_rgb[3 * i];
    sum += 0.2126 * std::min(p[0], 255.0f) + 0.7152 * std::min(p[1], 255.0f) +
           0.0722 * std::min(p[2], 255.0f);
  }
  return n > 0 ? sum / (255.0 * static_cast<double>(n)) : 0.0;
}

std::array<float, 3> SensorColourGains(const SimSensorOptions& sensor,
                                       const std::vector<float>& linear_rgb, double stamp) {
  double exposure = 1.0;
  if (sensor.auto_exposure > 0.0) {
    const double mean = MeanLuminance(linear_rgb);
    exposure = mean > 0.0 ? std::pow(sensor.exposure_target / mean, sensor.auto_exposure)
                          : kMaxAutoGain;
    exposure = std::clamp(exposure, 1.0 / kMaxAutoGain, kMaxAutoGain);
  }
  const double period = sensor.drift_period_s;
  if (sensor.exposure_drift > 0.0) {
    exposure *= 1.0 + sensor.exposure_drift * SensorDrift(sensor.seed, 0, stamp, period);
  }
  std::array<double, 3> g = {exposure, exposure, exposure};
  if (sensor.white_balance_drift > 0.0) {
    g[0] *= 1.0 + sensor.white_balance_drift * SensorDrift(sensor.seed, 1, stamp, period);
    g[2] *= 1.0 + sensor.white_balance_drift * SensorDrift(sensor.seed, 2, stamp, period);
  }
  return {static_cast<float>(g[0]), static_cast<float>(g[1]), static_cast<float>(g[2])};
}

void QuantizeRgb(const std::vector<float>& linear_rgb, int w, int h,
                 const std::array<float, 3>& gains, cv::Mat* rgb) {
  rgb->create(h, w, CV_8UC3);
  const bool unit = gains[0] == 1.0f && gains[1] == 1.0f && gains[2] == 1.0f;
  for (int v = 0; v < h; ++v) {
    std::uint8_t* row = rgb->ptr<std::uint8_t>(v);
    const float* in = &linear_rgb[static_cast<std::size_t>(v) * w * 3];
    if (unit) {  // the exact render: no multiplication, so its pixels never change
      for (int k = 0; k < 3 * w; ++k) row[k] = To8Bit(in[k] + 0.5f);
    } else {
      for (int k = 0; k < 3 * w; ++k) row[k] = To8Bit(in[k] * gains[k % 3] + 0.5f);
    }
  }
}

void ApplySensorNoise(const SimSensorOptions& sensor, std::uint64_t key,
                      const std::vector<float>& incidence_cos, RgbdSample* out) {
  const float cos_graze = sensor.grazing_angle_deg > 0.0
                              ? static_cast<float>(std::cos(sensor.grazing_angle_deg * M_PI / 180.0))
                              : -1.0f;
  const auto rgb_sigma = static_cast<float>(sensor.rgb_noise_sigma);
  const auto dropout = static_cast<float>(sensor.depth_dropout);
  const int w = out->depth.cols, h = out->depth.rows;
  for (int v = 0; v < h; ++v) {
    float* depth_row = out->depth.ptr<float>(v);
    std::uint8_t* rgb_row = out->rgb.ptr<std::uint8_t>(v);
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      // Counter-based randomness: two 64-bit hashes per pixel, no generator state, the same
      // numbers on every platform and standard library.
      const std::uint64_t r1 = Mix64(key + 2 * i), r2 = Mix64(key + 2 * i + 1);
      float z = depth_row[u];
      if (z > 0.0f) {
        if ((sensor.max_range > 0.0 && z > sensor.max_range) ||
            (sensor.min_range > 0.0 && z < sensor.min_range) || incidence_cos[i] < cos_graze) {
          z = 0.0f;
        } else if (dropout > 0.0f && Uniform16(r2 >> 48) < dropout) {
          z = 0.0f;
        } else if (sensor.depth_noise_sigma > 0.0 || sensor.depth_noise_quadratic > 0.0) {
          const float sigma =
              static_cast<float>(sensor.depth_noise_sigma + sensor.depth_noise_quadratic * z * z);
          z = std::max(0.0f, z + sigma * Gaussian4(r1));
        }
        depth_row[u] = z;
      }
      if (rgb_sigma > 0.0f) {
        for (int k = 0; k < 3; ++k) {
          const float noise = rgb_sigma * Gaussian4(Mix64(r2 + 0x9e3779b97f4a7c15ull * (k + 1)));
          rgb_row[3 * u + k] = To8Bit(rgb_row[3 * u + k] + noise + 0.5f);
        }
      }
    }
  }
}

}  // namespace p2i::scene
