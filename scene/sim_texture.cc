/// @file sim_texture.cc
/// @brief Procedural textures: hash-based value noise, tiles, wood grain, posters.
#include "scene/sim_texture.h"

#include <cmath>

namespace p2i::scene {
namespace {

inline std::uint32_t Hash(std::int32_t x, std::int32_t y, std::uint32_t seed) {
  std::uint32_t h = seed ^ 0x9e3779b9u;
  h ^= static_cast<std::uint32_t>(x) * 0x85ebca6bu;
  h = (h << 13) | (h >> 19);
  h ^= static_cast<std::uint32_t>(y) * 0xc2b2ae35u;
  h *= 0x27d4eb2fu;
  h ^= h >> 15;
  h *= 0x2c1b3c6du;
  h ^= h >> 12;
  return h;
}

inline float Unit(std::uint32_t h) { return static_cast<float>(h >> 8) * (1.0f / 16777216.0f); }

/// Smooth value noise in [0, 1].
inline float ValueNoise(float x, float y, std::uint32_t seed) {
  const float fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int32_t>(fx), iy = static_cast<std::int32_t>(fy);
  float tx = x - fx, ty = y - fy;
  tx = tx * tx * (3.0f - 2.0f * tx);
  ty = ty * ty * (3.0f - 2.0f * ty);
  const float a = Unit(Hash(ix, iy, seed)), b = Unit(Hash(ix + 1, iy, seed));
  const float c = Unit(Hash(ix, iy + 1, seed)), d = Unit(Hash(ix + 1, iy + 1, seed));
  const float ab = a + (b - a) * tx, cd = c + (d - c) * tx;
  return ab + (cd - ab) * ty;
}

inline float Fract(float x) { return x - std::floor(x); }

inline void Mix(const float* a, const float* b, float t, float* out) {
  for (int i = 0; i < 3; ++i) out[i] = a[i] + (b[i] - a[i]) * t;
}

}  // namespace

SimTextureSampler::SimTextureSampler(const SimMaterial& m)
    : texture_(m.texture), inv_scale_(static_cast<float>(1.0 / m.scale)), seed_(m.seed) {
  for (int i = 0; i < 3; ++i) {
    c1_[i] = static_cast<float>(m.color[i]);
    c2_[i] = static_cast<float>(m.color2[i]);
  }
}

void SimTextureSampler::Sample(float u, float v, float rgb[3]) const {
  const float su = u * inv_scale_, sv = v * inv_scale_;
  switch (texture_) {
    case SimTexture::kSolid:
      for (int i = 0; i < 3; ++i) rgb[i] = c1_[i];
      return;
    case SimTexture::kChecker: {
      const int parity = (static_cast<int>(std::floor(su)) + static_cast<int>(std::floor(sv))) & 1;
      const float* c = parity ? c2_ : c1_;
      // A faint 1 cm speckle keeps flat squares from being textureless.
      const float s =
          0.92f + 0.16f * Unit(Hash(static_cast<std::int32_t>(std::floor(u * 100.f)),
                                    static_cast<std::int32_t>(std::floor(v * 100.f)), seed_));
      for (int i = 0; i < 3; ++i) rgb[i] = c[i] * s;
      return;
    }
    case SimTexture::kTiles: {
      const float fu = Fract(su), fv = Fract(sv);
      constexpr float kGrout = 0.04f;
      if (fu < kGrout || fv < kGrout) {
        for (int i = 0; i < 3; ++i) rgb[i] = c2_[i];
        return;
      }
      const auto cu = static_cast<std::int32_t>(std::floor(su));
      const auto cv = static_cast<std::int32_t>(std::floor(sv));
      const float tile = 0.8f + 0.4f * Unit(Hash(cu, cv, seed_));
      const float speck = ValueNoise(u * 60.0f, v * 60.0f, seed_ + 1);
      const float s = tile * (0.85f + 0.3f * speck);
      for (int i = 0; i < 3; ++i) rgb[i] = c1_[i] * s;
      return;
    }
    case SimTexture::kWood: {
      // Grain runs along u: wavy rings across v plus fine streaks along the fibres.
      const float warp = ValueNoise(su * 0.7f, sv * 3.0f, seed_);
      const float ring = Fract(sv * 4.0f + warp * 2.5f);
      const float band = ring < 0.5f ? ring * 2.0f : 2.0f - ring * 2.0f;
      const float streak = ValueNoise(u * 8.0f, v * 300.0f, seed_ + 7);
      Mix(c1_, c2_, band * band, rgb);
      const float s = 0.85f + 0.3f * streak;
      for (int i = 0; i < 3; ++i) rgb[i] *= s;
      return;
    }
    case SimTexture::kNoise: {
      const float n = 0.5f * ValueNoise(su, sv, seed_) +
                      0.3f * ValueNoise(su * 4.f, sv * 4.f, seed_ + 3) +
                      0.2f * ValueNoise(u * 80.f, v * 80.f, seed_ + 5);
      Mix(c1_, c2_, n, rgb);
      return;
    }
    case SimTexture::kStripes: {
      const float t = Fract(su);
      const float w = t < 0.5f ? 1.0f : 0.0f;
      const float fine = 0.9f + 0.2f * Unit(Hash(static_cast<std::int32_t>(std::floor(v * 200.f)),
                                                 static_cast<std::int32_t>(std::floor(su)), seed_));
      Mix(c1_, c2_, w, rgb);
      for (int i = 0; i < 3; ++i) rgb[i] *= fine;
      return;
    }
    case SimTexture::kPoster: {
      // A grid of cells, each with its own high-frequency pattern and colour pair: sharp
      // edges and fine periodic detail that a blurry synthesis cannot reproduce.
      const auto cu = static_cast<std::int32_t>(std::floor(su));
      const auto cv = static_cast<std::int32_t>(std::floor(sv));
      const std::uint32_t h = Hash(cu, cv, seed_);
      const float lu = Fract(su), lv = Fract(sv);
      const float freq = 4.0f + static_cast<float>((h >> 4) & 7u) * 2.0f;  // per cell
      float t = 0.0f;
      switch (h & 3u) {
        case 0:  // stripes at an angle
          t = Fract((lu * (1.0f + ((h >> 8) & 1u)) + lv) * freq) < 0.5f ? 1.0f : 0.0f;
          break;
        case 1:  // fine checker
          t = static_cast<float>((static_cast<int>(lu * freq) + static_cast<int>(lv * freq)) & 1);
          break;
        case 2: {  // rings
          const float du = lu - 0.5f, dv = lv - 0.5f;
          t = Fract(std::sqrt(du * du + dv * dv) * freq * 2.0f) < 0.5f ? 1.0f : 0.0f;
          break;
        }
        default:  // "text": random blocks on a fine grid
          t = Unit(Hash(static_cast<std::int32_t>(lu * freq * 3.0f),
                        static_cast<std::int32_t>(lv * freq * 3.0f), h)) < 0.45f
                  ? 1.0f
                  : 0.0f;
          break;
      }
      float a[3], b[3];
      for (int i = 0; i < 3; ++i) {
        const float hue = Unit(Hash(cu * 3 + i, cv, seed_ + 11));
        a[i] = c1_[i] * (0.5f + 0.5f * hue);
        b[i] = c2_[i] * (0.4f + 0.6f * (1.0f - hue));
      }
      Mix(a, b, t, rgb);
      return;
    }
  }
}

}  // namespace p2i::scene
