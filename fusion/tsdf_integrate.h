/// @file tsdf_integrate.h
/// @brief The TSDF's integration kernel: one depth + colour frame into the voxel blocks it
/// touches, with the arithmetic of Open3D 0.16's VoxelBlockGrid::Integrate, float for float
/// (tests/fusion/tsdf_integrate_test.cc compares the saved volumes byte for byte), in less than
/// half its time. INTERNAL to fusion/ (TsdfVolume::Integrate fills these from its grid).
///
/// Why it is ours: Open3D's CPU kernel runs one generic work item per voxel, each dividing its
/// index back into block and voxel coordinates and going through its tensor indexers, over the
/// blocks in hash order (each reads another part of the frame from memory). This one walks each
/// block's voxels in order with per-row products, the blocks in the order they appear in the
/// image, with the same operations in the same order on every voxel it updates: a 640x480 frame
/// integrates in 11 ms instead of 23-25 in 8^3 blocks (docs/RESULTS.md "Our own integration
/// kernel").
#pragma once

#include <cstdint>

namespace p2i::fusion {

/// The frame, as Open3D's kernel takes it.
struct IntegrationFrame {
  const float* depth = nullptr;   ///< metres, row-major, width x height, 0 = invalid
  const std::uint8_t* colour = nullptr;  ///< RGB, 3 bytes per pixel; nullptr = depth only
  /// The float in [0, 1] each 8-bit value is for Open3D's kernel: 256 entries, as OpenCV's
  /// convertTo(CV_32F, 1 / 255.0) makes them (TsdfVolume converts the frame that way for it).
  const float* colour_values = nullptr;
  int width = 0;
  int height = 0;
  /// Pinhole intrinsic (Open3D's: the principal point as TsdfVolume passes it, shifted by half a
  /// pixel so that truncating a projection picks the nearest pixel).
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double extrinsic[3][4] = {};  ///< world to camera, rows of the 4x4
  float depth_max_m = 0.0f;     ///< measurements farther away are skipped
};

/// The voxel storage of a block grid: Open3D's hash map buffers (tsdf, weight, colour per voxel,
/// structure of arrays, block b's voxel (x, y, z) at b * r^3 + (z * r + y) * r + x).
struct VoxelBlocks {
  int resolution = 0;        ///< voxels per block edge (r)
  float voxel_size = 0.0f;   ///< metres
  float sdf_trunc = 0.0f;    ///< metres: voxel_size * the truncation in voxels (float product)
  const int* keys = nullptr; ///< block coordinates (x, y, z) per buffer index
  float* tsdf = nullptr;
  float* weight = nullptr;
  float* colour = nullptr;   ///< 3 per voxel, 0-255 as Open3D keeps float colours
};

/// Integrates `frame` into the `n` blocks at buffer indices `blocks` (activated beforehand), on
/// `threads` OpenMP threads (blocks are independent: the result does not depend on it).
void IntegrateBlocks(const VoxelBlocks& grid, const int* blocks, int64_t n, const IntegrationFrame& frame,
                     int threads);

}  // namespace p2i::fusion
