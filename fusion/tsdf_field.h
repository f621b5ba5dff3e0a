/// @file tsdf_field.h
/// @brief Trilinear reading of a sparse block TSDF and the sub-voxel refinement of a raycast hit.
///
/// Open3D 0.16's VoxelBlockGrid::RayCast finds the zero crossing from *nearest-voxel* TSDF values
/// read with a floor (the voxel (i, j, k) holds the value at (i, j, k) x voxel_size, but every
/// point of the cell [i, i + 1) reads it): the sampled field is a staircase shifted by up to one
/// voxel, and its crossing is off by up to a voxel along the ray, more at grazing angles
/// (measured on a fused plane seen at 30 degrees with 1 cm voxels: depth errors of up to 2 % in a
/// pattern that follows the voxel grid). This file reads the same voxels trilinearly, as Open3D
/// does for normals and colour, and moves each hit onto the trilinear field's zero crossing.
/// No Open3D type here: the caller hands over raw pointers to the grid's tsdf and weight arrays.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

namespace p2i::fusion {

class TsdfField {
 public:
  /// `tsdf` and `weight` are the grid's per-voxel arrays, laid out per block buffer index as
  /// [block][z][y][x] (Open3D's layout), block_resolution^3 floats per block. Not owned.
  TsdfField(float voxel_size, int block_resolution, const float* tsdf, const float* weight);

  /// Registers the block with integer key (bx, by, bz) stored at `buffer_index`.
  void AddBlock(int bx, int by, int bz, int64_t buffer_index);
  /// After the last AddBlock: replaces the hash lookups by a dense table over the blocks'
  /// bounding box when it has at most kMaxDenseCells cells (a room at 2 cm voxels has a few
  /// thousand); reads are the same either way, only faster. Optional.
  void Seal();
  static constexpr int64_t kMaxDenseCells = int64_t{1} << 22;

  /// Trilinear TSDF at world point p (voxel values at integer multiples of the voxel size).
  /// False where any of the 8 voxels around p is not allocated or was never observed.
  bool Sample(const Eigen::Vector3f& p, float* value) const;

  /// Hits are moved by at most this many voxels along the ray.
  static constexpr float kMaxShiftVoxels = 6.0f;

  /// The zero crossing of the trilinear field on the ray o + t d near t0 (t in the units of d,
  /// e.g. z-depth for a d with d.z() = 1 in the camera frame): two secant steps on a bracket of
  /// +-half a voxel around t0; where that bracket holds no crossing (front > 0 before back <= 0),
  /// a half-voxel march from three voxels before t0 up to kMaxShiftVoxels after it. Returns t0 where
  /// neither finds one.
  float RefineHit(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t0) const;

  /// Marches the ray o + t d from t_begin to t_end in half-voxel steps and returns the first zero
  /// crossing (front > 0 to back <= 0, both observed), refined as RefineHit does; 0 = none. For
  /// the pixels Open3D's raycast misses (it steps by the TSDF value, which at grazing angles jumps
  /// over the whole band behind a surface).
  float FindCrossing(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t_begin, float t_end) const;

 private:
  float March(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t_begin, float t_end) const;
  static int64_t Key(int64_t bx, int64_t by, int64_t bz);
  /// Buffer index of the voxel's block, or -1; `local` is the voxel's index inside the block.
  int64_t Find(int64_t vx, int64_t vy, int64_t vz, int64_t* local) const;

  float voxel_;
  int res_;
  const float* tsdf_;
  const float* weight_;
  /// Buffer index of block (bx, by, bz), or -1.
  int64_t BlockIndex(int64_t bx, int64_t by, int64_t bz) const;
  /// The block coordinate of voxel coordinate v (floor of v / res_).
  int64_t BlockOf(int64_t v) const;

  int shift_ = -1;  ///< log2(res_) when res_ is a power of two (shifts and masks instead of divisions)
  std::unordered_map<int64_t, int64_t> blocks_;
  // Bounding box of the blocks (block units) and, once sealed, the dense table over it.
  int64_t lo_[3] = {0, 0, 0}, hi_[3] = {-1, -1, -1};
  std::vector<int64_t> dense_;
  uint64_t dims_[3] = {0, 0, 0};  ///< the dense table's size per axis (blocks)
};

// The block lookups of every trilinear read, inline (the library is built with -fPIC: calls between
// its own exported functions would go through the PLT and could not be inlined).

inline int64_t TsdfField::BlockIndex(int64_t bx, int64_t by, int64_t bz) const {
  if (!dense_.empty()) {
    // One unsigned compare per axis: below lo_ wraps to a huge value.
    const uint64_t x = static_cast<uint64_t>(bx - lo_[0]), y = static_cast<uint64_t>(by - lo_[1]),
                   z = static_cast<uint64_t>(bz - lo_[2]);
    if (x >= dims_[0] || y >= dims_[1] || z >= dims_[2]) return -1;
    return dense_[(z * dims_[1] + y) * dims_[0] + x];
  }
  const auto it = blocks_.find(Key(bx, by, bz));
  return it == blocks_.end() ? -1 : it->second;
}

inline int64_t TsdfField::BlockOf(int64_t v) const {
  if (shift_ >= 0) return v >> shift_;  // arithmetic shifts floor negative voxel indices too
  return v >= 0 ? v / res_ : -((-v + res_ - 1) / res_);
}

inline int64_t TsdfField::Find(int64_t vx, int64_t vy, int64_t vz, int64_t* local) const {
  const int64_t bx = BlockOf(vx), by = BlockOf(vy), bz = BlockOf(vz);
  const int64_t block = BlockIndex(bx, by, bz);
  if (block < 0) return -1;
  *local = ((vz - bz * res_) * res_ + (vy - by * res_)) * res_ + (vx - bx * res_);
  return block;
}

}  // namespace p2i::fusion
