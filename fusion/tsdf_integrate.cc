/// @file tsdf_integrate.cc
/// @brief IntegrateBlocks: Open3D 0.16's TSDF integration (VoxelBlockGridImpl.h, IntegrateCPU),
/// the same float operations in the same order per voxel, walked block by block.
#include "fusion/tsdf_integrate.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace p2i::fusion {
namespace {

constexpr int kMaxResolution = 64;  // TsdfOptions::Validate's bound

/// Open3D's TransformIndexer keeps its matrices in float.
struct FloatCamera {
  float e[3][4];
  float fx, fy, cx, cy;
  explicit FloatCamera(const IntegrationFrame& f) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j) e[i][j] = static_cast<float>(f.extrinsic[i][j]);
    fx = static_cast<float>(f.fx);
    fy = static_cast<float>(f.fy);
    cx = static_cast<float>(f.cx);
    cy = static_cast<float>(f.cy);
  }
};

/// Where Open3D reads a voxel's colour: it unprojects the depth pixel (ui, vi) at depth 1 and
/// projects it back with the colour intrinsic (equal to the depth one here), then rounds. Each
/// coordinate depends on ui or vi alone, so both are tabulated once per frame with Open3D's
/// operations: -1 where the colour image's boundary check fails.
struct ColourPixels {
  std::vector<int> u, v;
  ColourPixels(const IntegrationFrame& f, const FloatCamera& c) : u(f.width, -1), v(f.height, -1) {
    const float wmax = static_cast<float>(f.width) - 1.0f, hmax = static_cast<float>(f.height) - 1.0f;
    const float inv1 = 1.0f / 1.0f;
    for (int ui = 0; ui < f.width; ++ui) {
      const float x1 = (static_cast<float>(ui) - c.cx) * 1.0f / c.fx;
      const float uf = c.fx * x1 * inv1 + c.cx;
      if (uf >= 0 && uf <= wmax) u[ui] = static_cast<int>(std::round(uf));
    }
    for (int vi = 0; vi < f.height; ++vi) {
      const float y1 = (static_cast<float>(vi) - c.cy) * 1.0f / c.fy;
      const float vf = c.fy * y1 * inv1 + c.cy;
      if (vf >= 0 && vf <= hmax) v[vi] = static_cast<int>(std::round(vf));
    }
  }
};

/// One block. Open3D computes, per voxel at integer world-voxel coordinates (x, y, z):
///   xs = float(x) * voxel_size (and ys, zs); xc = xs*e00 + ys*e01 + zs*e02 + e03 (left to right)
/// The three products depend on one coordinate each, so they are computed once per row/column/
/// layer here and summed in Open3D's order: the same floats.
void IntegrateBlock(const VoxelBlocks& g, int block, const IntegrationFrame& f, const FloatCamera& c,
                    const ColourPixels& cp) {
  const int r = g.resolution;
  const int* key = g.keys + 3 * static_cast<int64_t>(block);
  float px[3][kMaxResolution], py[3][kMaxResolution], pz[3][kMaxResolution];
  for (int v = 0; v < r; ++v) {
    const float xs = static_cast<float>(key[0] * r + v) * g.voxel_size;
    const float ys = static_cast<float>(key[1] * r + v) * g.voxel_size;
    const float zs = static_cast<float>(key[2] * r + v) * g.voxel_size;
    for (int i = 0; i < 3; ++i) {
      px[i][v] = xs * c.e[i][0];
      py[i][v] = ys * c.e[i][1];
      pz[i][v] = zs * c.e[i][2];
    }
  }
  const float wmax = static_cast<float>(f.width) - 1.0f;
  const float hmax = static_cast<float>(f.height) - 1.0f;
  const int64_t r3 = static_cast<int64_t>(r) * r * r;
  float* tsdf = g.tsdf + block * r3;
  float* weight = g.weight + block * r3;
  float* colour = g.colour != nullptr ? g.colour + 3 * block * r3 : nullptr;
  const float trunc = g.sdf_trunc;
  int64_t i = 0;
  for (int zv = 0; zv < r; ++zv) {
    for (int yv = 0; yv < r; ++yv) {
      for (int xv = 0; xv < r; ++xv, ++i) {
        const float xc = ((px[0][xv] + py[0][yv]) + pz[0][zv]) + c.e[0][3];
        const float yc = ((px[1][xv] + py[1][yv]) + pz[1][zv]) + c.e[1][3];
        const float zc = ((px[2][xv] + py[2][yv]) + pz[2][zv]) + c.e[2][3];
        const float inv_z = 1.0f / zc;
        const float u = c.fx * xc * inv_z + c.cx;
        const float v = c.fy * yc * inv_z + c.cy;
        if (!(v >= 0 && u >= 0 && v <= hmax && u <= wmax)) continue;
        const int ui = static_cast<int>(u);
        const int vi = static_cast<int>(v);
        const int64_t pixel = static_cast<int64_t>(vi) * f.width + ui;
        const float depth = f.depth[pixel] / 1.0f;
        float sdf = depth - zc;
        if (depth <= 0 || depth > f.depth_max_m || zc <= 0 || sdf < -trunc) continue;
        sdf = sdf < trunc ? sdf : trunc;
        sdf /= trunc;
        const float w = weight[i];
        const float inv_wsum = 1.0f / (w + 1);
        tsdf[i] = (w * tsdf[i] + sdf) * inv_wsum;
        if (colour != nullptr && f.colour != nullptr) {
          const int cu = cp.u[ui], cv = cp.v[vi];
          if (cu >= 0 && cv >= 0) {
            const std::uint8_t* in = f.colour + 3 * (static_cast<int64_t>(cv) * f.width + cu);
            float* out = colour + 3 * i;
            for (int k = 0; k < 3; ++k) out[k] = (w * out[k] + f.colour_values[in[k]] * 255.0f) * inv_wsum;
          }
        }
        weight[i] = w + 1;
      }
    }
  }
}

}  // namespace

void IntegrateBlocks(const VoxelBlocks& grid, const int* blocks, int64_t n, const IntegrationFrame& frame,
                     int threads) {
  const FloatCamera camera(frame);
  const ColourPixels colour_pixels(frame, camera);
  // Blocks in the order their centres appear in the image (rows of 16 pixels, then columns):
  // neighbouring blocks read the same lines of the frame while they are in cache. Each block is
  // updated on its own, so the order changes no value.
  std::vector<std::pair<int64_t, int>> order(static_cast<size_t>(n));
  const float half = 0.5f * static_cast<float>(grid.resolution) * grid.voxel_size;
  for (int64_t b = 0; b < n; ++b) {
    const int* key = grid.keys + 3 * static_cast<int64_t>(blocks[b]);
    float p[3];
    for (int i = 0; i < 3; ++i) {
      p[i] = camera.e[i][3];
      for (int j = 0; j < 3; ++j)
        p[i] += camera.e[i][j] * (static_cast<float>(key[j] * grid.resolution) * grid.voxel_size + half);
    }
    // Clamped before the conversion (NaN to 0): a centre near the camera's plane projects far out.
    const auto pixel = [](float x) { return static_cast<int64_t>(x > 0.0f ? std::min(x, 1e9f) : 0.0f); };
    int64_t row = 0, col = 0;
    if (p[2] > 0.0f) {
      row = pixel((camera.fy * p[1] / p[2] + camera.cy) / 16.0f);
      col = pixel(camera.fx * p[0] / p[2] + camera.cx);
    }
    order[static_cast<size_t>(b)] = {(row << 30) + col, blocks[b]};
  }
  std::sort(order.begin(), order.end());
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int64_t b = 0; b < n; ++b) IntegrateBlock(grid, order[static_cast<size_t>(b)].second, frame, camera, colour_pixels);
}

}  // namespace p2i::fusion
