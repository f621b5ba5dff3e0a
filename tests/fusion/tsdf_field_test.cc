/// @file tsdf_field_test.cc
/// @brief TsdfField: trilinear reads across blocks, and hits moved onto the zero crossing.
#include <vector>

#include <catch2/catch.hpp>

#include "fusion/tsdf_field.h"

namespace p2i::fusion {
namespace {

/// Two 4^3 blocks side by side along z (keys (0,0,0) and (0,0,1)) holding a linear field with
/// its zero at world z = z0: tsdf = (z0 - z) / 0.04 (front positive), all observed.
struct TwoBlocks {
  static constexpr int kRes = 4;
  static constexpr float kVoxel = 0.01f;
  float z0 = 0.047f;
  std::vector<float> tsdf, weight;
  TwoBlocks() : tsdf(2 * kRes * kRes * kRes), weight(2 * kRes * kRes * kRes, 1.0f) {
    for (int b = 0; b < 2; ++b)
      for (int z = 0; z < kRes; ++z)
        for (int y = 0; y < kRes; ++y)
          for (int x = 0; x < kRes; ++x) {
            const float wz = (b * kRes + z) * kVoxel;
            tsdf[((b * kRes + z) * kRes + y) * kRes + x] = (z0 - wz) / 0.04f;
          }
  }
  /// sealed: the dense block table (TsdfField::Seal), else the hash lookups; reads must agree.
  TsdfField Field(bool sealed) const {
    TsdfField f(kVoxel, kRes, tsdf.data(), weight.data());
    f.AddBlock(0, 0, 0, 0);
    f.AddBlock(0, 0, 1, 1);
    if (sealed) f.Seal();
    return f;
  }
};

TEST_CASE("TsdfField: trilinear reads are exact on a linear field, also across a block edge", "[unit]") {
  const TwoBlocks g;
  const bool sealed = GENERATE(false, true);
  INFO("sealed " << sealed);
  const TsdfField f = g.Field(sealed);
  float v = 0.0f;
  for (float z : {0.005f, 0.0333f, 0.039f, 0.0412f, 0.055f}) {
    REQUIRE(f.Sample(Eigen::Vector3f(0.012f, 0.017f, z), &v));
    CHECK(v == Approx((g.z0 - z) / 0.04f).margin(1e-5));
  }
  CHECK_FALSE(f.Sample(Eigen::Vector3f(0.012f, 0.017f, 0.075f), &v));  // needs block (0,0,2)
  CHECK_FALSE(f.Sample(Eigen::Vector3f(-0.002f, 0.017f, 0.02f), &v));  // needs block (-1,0,0)
  std::vector<float> w = g.weight;
  w[((0 * 4 + 2) * 4 + 1) * 4 + 1] = 0.0f;  // one voxel never observed
  TsdfField holed(0.01f, 4, g.tsdf.data(), w.data());
  holed.AddBlock(0, 0, 0, 0);
  if (sealed) holed.Seal();
  CHECK_FALSE(holed.Sample(Eigen::Vector3f(0.012f, 0.017f, 0.025f), &v));
  // A missing block inside the bounding box of the others: (0,0,1) between (0,0,0) and (0,0,2).
  TsdfField gap(0.01f, 4, g.tsdf.data(), g.weight.data());
  gap.AddBlock(0, 0, 0, 0);
  gap.AddBlock(0, 0, 2, 1);
  if (sealed) gap.Seal();
  CHECK(gap.Sample(Eigen::Vector3f(0.012f, 0.017f, 0.02f), &v));
  CHECK_FALSE(gap.Sample(Eigen::Vector3f(0.012f, 0.017f, 0.05f), &v));
  CHECK(gap.Sample(Eigen::Vector3f(0.012f, 0.017f, 0.09f), &v));
}

TEST_CASE("TsdfField: a hit up to a few voxels off moves onto the crossing, a hopeless one stays", "[unit]") {
  const TwoBlocks g;
  const bool sealed = GENERATE(false, true);
  INFO("sealed " << sealed);
  const TsdfField f = g.Field(sealed);
  const Eigen::Vector3f o(0.015f, 0.015f, 0.0f), d(0.0f, 0.0f, 1.0f);
  for (float t0 : {0.047f, 0.044f, 0.05f, 0.025f, 0.058f})
    CHECK(f.RefineHit(o, d, t0) == Approx(g.z0).margin(1e-4));
  CHECK(f.RefineHit(o, d, 0.075f) == Approx(g.z0).margin(1e-4));  // 2.8 voxels late: the march finds it
  CHECK(f.RefineHit(o, d, 0.11f) == 0.11f);  // 6 voxels late, past the blocks: unchanged
  CHECK(f.FindCrossing(o, d, 0.0f, 0.07f) == Approx(g.z0).margin(1e-4));
  CHECK(f.FindCrossing(o, d, 0.05f, 0.07f) == 0.0f);  // begins behind the surface
}

}  // namespace
}  // namespace p2i::fusion
