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

/// Where a texture is sampled: (u, v) in metres on the surface and (su, sv) = (u, v) / scale.
struct TexCoord {
  float u, v, su, sv;
};

void Checker(const TexCoord& p, const float* c1, const float* c2, std::uint32_t seed,
             float* rgb) {
  const int parity =
      (static_cast<int>(std::floor(p.su)) + static_cast<int>(std::floor(p.sv))) & 1;
  const float* c = parity ? c2 : c1;
  // A faint 1 cm speckle keeps flat squares from being textureless.
  const float s =
      0.92f + 0.16f * Unit(Hash(static_cast<std::int32_t>(std::floor(p.u * 100.f)),
                                static_cast<std::int32_t>(std::floor(p.v * 100.f)), seed));
  for (int i = 0; i < 3; ++i) rgb[i] = c[i] * s;
}

void Tiles(const TexCoord& p, const float* c1, const float* c2, std::uint32_t seed, float* rgb) {
  const float fu = Fract(p.su), fv = Fract(p.sv);
  constexpr float kGrout = 0.04f;
  if (fu < kGrout || fv < kGrout) {
    for (int i = 0; i < 3; ++i) rgb[i] = c2[i];
    return;
  }
  const auto cu = static_cast<std::int32_t>(std::floor(p.su));
  const auto cv = static_cast<std::int32_t>(std::floor(p.sv));
  const float tile = 0.8f + 0.4f * Unit(Hash(cu, cv, seed));
  const float speck = ValueNoise(p.u * 60.0f, p.v * 60.0f, seed + 1);
  const float s = tile * (0.85f + 0.3f * speck);
  for (int i = 0; i < 3; ++i) rgb[i] = c1[i] * s;
}

void Wood(const TexCoord& p, const float* c1, const float* c2, std::uint32_t seed, float* rgb) {
  // Grain runs along u: wavy rings across v plus fine streaks along the fibres.
  const float warp = ValueNoise(p.su * 0.7f, p.sv * 3.0f, seed);
  const float ring = Fract(p.sv * 4.0f + warp * 2.5f);
  const float band = ring < 0.5f ? ring * 2.0f : 2.0f - ring * 2.0f;
  const float streak = ValueNoise(p.u * 8.0f, p.v * 300.0f, seed + 7);
  Mix(c1, c2, band * band, rgb);
  const float s = 0.85f + 0.3f * streak;
  for (int i = 0; i < 3; ++i) rgb[i] *= s;
}

void Noise(const TexCoord& p, const float* c1, const float* c2, std::uint32_t seed, float* rgb) {
  const float n = 0.5f * ValueNoise(p.su, p.sv, seed) +
                  0.3f * ValueNoise(p.su * 4.f, p.sv * 4.f, seed + 3) +
                  0.2f * ValueNoise(p.u * 80.f, p.v * 80.f, seed + 5);
  Mix(c1, c2, n, rgb);
}

void Stripes(const TexCoord& p, const float* c1, const float* c2, std::uint32_t seed,
             float* rgb) {
  const float t = Fract(p.su);
  const float w = t < 0.5f ? 1.0f : 0.0f;
  const float fine = 0.9f + 0.2f * Unit(Hash(static_cast<std::int32_t>(std::floor(p.v * 200.f)),
                                             static_cast<std::int32_t>(std::floor(p.su)), seed));
  Mix(c1, c2, w, rgb);
  for (int i = 0; i < 3; ++i) rgb[i] *= fine;
}

/// A grid of cells, each with its own high-frequency pattern and colour pair: sharp edges and
/// fine periodic detail that a blurry synthesis cannot reproduce.
void Poster(const TexCoord& p, const float* c1, const float* c2, std::uint32_t seed,
            float* rgb) {
  const auto cu = static_cast<std::int32_t>(std::floor(p.su));
  const auto cv = static_cast<std::int32_t>(std::floor(p.sv));
  const std::uint32_t h = Hash(cu, cv, seed);
  const float lu = Fract(p.su), lv = Fract(p.sv);
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
    const float hue = Unit(Hash(cu * 3 + i, cv, seed + 11));
    a[i] = c1[i] * (0.5f + 0.5f * hue);
    b[i] = c2[i] * (0.4f + 0.6f * (1.0f - hue));
  }
  Mix(a, b, t, rgb);
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
  const TexCoord p{u, v, u * inv_scale_, v * inv_scale_};
  switch (texture_) {
    case SimTexture::kSolid:
      for (int i = 0; i < 3; ++i) rgb[i] = c1_[i];
      return;
    case SimTexture::kChecker:
      return Checker(p, c1_, c2_, seed_, rgb);
    case SimTexture::kTiles:
      return Tiles(p, c1_, c2_, seed_, rgb);
    case SimTexture::kWood:
      return Wood(p, c1_, c2_, seed_, rgb);
    case SimTexture::kNoise:
      return Noise(p, c1_, c2_, seed_, rgb);
    case SimTexture::kStripes:
      return Stripes(p, c1_, c2_, seed_, rgb);
    case SimTexture::kPoster:
      return Poster(p, c1_, c2_, seed_, rgb);
  }
}

}  // namespace p2i::scene
