/// @file tsdf_field.cc
/// @brief TsdfField: trilinear TSDF over sparse blocks and the secant refinement of hits.
#include "fusion/tsdf_field.h"

#include <cmath>

namespace p2i::fusion {

TsdfField::TsdfField(float voxel_size, int block_resolution, const float* tsdf, const float* weight)
    : voxel_(voxel_size), res_(block_resolution), tsdf_(tsdf), weight_(weight) {
  for (int s = 0; s < 8; ++s)
    if ((1 << s) == res_) shift_ = s;
}

int64_t TsdfField::Key(int64_t bx, int64_t by, int64_t bz) {
  constexpr int64_t kOffset = int64_t{1} << 20, kMask = (int64_t{1} << 21) - 1;
  return (((bx + kOffset) & kMask) << 42) | (((by + kOffset) & kMask) << 21) | ((bz + kOffset) & kMask);
}

void TsdfField::AddBlock(int bx, int by, int bz, int64_t buffer_index) {
  const int64_t b[3] = {bx, by, bz};
  for (int a = 0; a < 3; ++a) {
    if (blocks_.empty() || b[a] < lo_[a]) lo_[a] = b[a];
    if (blocks_.empty() || b[a] > hi_[a]) hi_[a] = b[a];
  }
  blocks_[Key(bx, by, bz)] = buffer_index;
  dense_.clear();  // stale until the next Seal()
}

void TsdfField::Seal() {
  dense_.clear();
  if (blocks_.empty()) return;
  const int64_t nx = hi_[0] - lo_[0] + 1, ny = hi_[1] - lo_[1] + 1, nz = hi_[2] - lo_[2] + 1;
  if (nx * ny * nz > kMaxDenseCells) return;
  dense_.assign(static_cast<size_t>(nx * ny * nz), -1);
  dims_[0] = static_cast<uint64_t>(nx), dims_[1] = static_cast<uint64_t>(ny), dims_[2] = static_cast<uint64_t>(nz);
  for (int64_t z = 0; z < nz; ++z)
    for (int64_t y = 0; y < ny; ++y)
      for (int64_t x = 0; x < nx; ++x) {
        const auto it = blocks_.find(Key(lo_[0] + x, lo_[1] + y, lo_[2] + z));
        if (it != blocks_.end()) dense_[static_cast<size_t>((z * ny + y) * nx + x)] = it->second;
      }
}

bool TsdfField::Sample(const Eigen::Vector3f& p, float* value) const {
  const Eigen::Vector3f q = p / voxel_;
  const float fx = std::floor(q.x()), fy = std::floor(q.y()), fz = std::floor(q.z());
  const float rx = q.x() - fx, ry = q.y() - fy, rz = q.z() - fz;
  const int64_t x0 = static_cast<int64_t>(fx), y0 = static_cast<int64_t>(fy), z0 = static_cast<int64_t>(fz);
  const int64_t res3 = static_cast<int64_t>(res_) * res_ * res_;
  // Most cells lie inside one block: one block lookup serves all eight corners (the lookups were
  // most of the hit refinement's cost); a cell across a block edge looks each corner up.
  const int64_t bx = BlockOf(x0), by = BlockOf(y0), bz = BlockOf(z0);
  const int64_t lx = x0 - bx * res_, ly = y0 - by * res_, lz = z0 - bz * res_;
  const bool one_block = lx + 1 < res_ && ly + 1 < res_ && lz + 1 < res_;
  int64_t base = 0;
  if (one_block) {
    const int64_t block = BlockIndex(bx, by, bz);
    if (block < 0) return false;
    base = block * res3 + (lz * res_ + ly) * res_ + lx;
  }
  float sum = 0.0f;
  for (int k = 0; k < 8; ++k) {
    const int dx = k & 1, dy = (k >> 1) & 1, dz = (k >> 2) & 1;
    int64_t i = base + (static_cast<int64_t>(dz) * res_ + dy) * res_ + dx;
    if (!one_block) {
      int64_t local = 0;
      const int64_t block = Find(x0 + dx, y0 + dy, z0 + dz, &local);
      if (block < 0) return false;
      i = block * res3 + local;
    }
    if (!(weight_[i] > 0.0f)) return false;
    const float w = (dx ? rx : 1.0f - rx) * (dy ? ry : 1.0f - ry) * (dz ? rz : 1.0f - rz);
    sum += w * tsdf_[i];
  }
  *value = sum;
  return true;
}

float TsdfField::RefineHit(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t0) const {
  const float len = d.norm();
  if (!(len > 0.0f) || !(t0 > 0.0f)) return t0;
  const float half = 0.5f * voxel_ / len;  // half a voxel along the ray, in units of t
  auto at = [&](float t, float* f) { return Sample(o + t * d, f); };
  auto secant = [&](float a, float b, float* t) {
    float fa = 0.0f, fb = 0.0f;
    if (!at(a, &fa) || !at(b, &fb) || !(fa > 0.0f) || fb > 0.0f) return false;
    *t = a + (b - a) * fa / (fa - fb);
    return true;
  };
  float t = t0;
  if (!secant(t0 - half, t0 + half, &t)) {
    // Open3D's crossing is not within half a voxel of the trilinear one (measured: up to 2.4
    // voxels early, 1.5 late on a plane seen at 30 degrees): march from three voxels before it.
    const float found = March(o, d, t0 - 6.0f * half, t0 + 2.0f * kMaxShiftVoxels * half);
    return found > 0.0f ? found : t0;
  }
  // A second secant step on a bracket of a quarter voxel around the first estimate.
  float t2 = t;
  if (secant(t - 0.5f * half, t + 0.5f * half, &t2)) t = t2;
  return std::abs(t - t0) <= 2.0f * kMaxShiftVoxels * half ? t : t0;
}

float TsdfField::March(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t_begin,
                       float t_end) const {
  const float len = d.norm();
  if (!(len > 0.0f) || !(t_end > t_begin)) return 0.0f;
  const float step = 0.5f * voxel_ / len;
  float prev = 0.0f;
  bool have_prev = false;
  for (float t = t_begin; t <= t_end; t += step) {
    float f = 0.0f;
    if (!Sample(o + t * d, &f)) {
      have_prev = false;
      continue;
    }
    if (have_prev && prev > 0.0f && f <= 0.0f) {
      const float a = t - step;
      float t1 = a + step * prev / (prev - f), fa = 0.0f, fb = 0.0f;
      // One more secant step on a quarter-voxel bracket.
      const float lo = t1 - 0.5f * step, hi = t1 + 0.5f * step;
      if (Sample(o + lo * d, &fa) && Sample(o + hi * d, &fb) && fa > 0.0f && fb <= 0.0f)
        t1 = lo + (hi - lo) * fa / (fa - fb);
      return t1;
    }
    prev = f;
    have_prev = true;
  }
  return 0.0f;
}

float TsdfField::FindCrossing(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t_begin,
                              float t_end) const {
  return March(o, d, t_begin, t_end);
}

}  // namespace p2i::fusion
