/// @file tsdf_volume.h
/// @brief A growing TSDF of RGB-D frames (Open3D's t::geometry::VoxelBlockGrid behind a pimpl:
/// no Open3D type in this header) with a raycast of depth, normals and voxel colour at any pose
/// and camera.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"

namespace YAML {
class Node;
}  // namespace YAML

namespace p2i::fusion {

struct TsdfOptions {
  double voxel_size_m = 0.02;     ///< edge of one voxel
  /// Voxels per block edge (blocks are allocated sparsely), or 0 = auto (the YAML's `auto`, the
  /// default): ForFrames picks 8 when a pixel of the frames, at depth_max_m, is no wider than a
  /// voxel, else 16. Dense frames (640x480, 320x240) put a ray through every voxel near a surface,
  /// and 8^3 blocks integrate a 640x480 frame ~30 % faster than 16^3 at half the memory and the
  /// same views; coarse frames (128x128, 48x36) leave 8^3 blocks that no ray reached between
  /// their pixels, holes in the surface (docs/RESULTS.md "Blocks sized to the frames").
  int block_resolution = 0;
  /// Hash map capacity at start; it doubles when the blocks fill it. Open3D allocates and writes
  /// the voxel data of the whole capacity (2000 blocks: 20 MB in 8^3 blocks, 164 MB in 16^3), and
  /// the frame that fills it waits for the doubling (~0.5 s for a room in 8^3 blocks on the
  /// project's VMs): a larger value moves that cost to construction (docs/RESULTS.md "What the
  /// TSDF's memory costs in time").
  int initial_blocks = 2000;
  /// SDF truncation in voxels (Open3D's trunc_voxel_multiplier): the band fused around each
  /// measured surface. Larger closes thin gaps, smaller keeps thin objects apart.
  double trunc_voxels = 4.0;
  double depth_min_m = 0.1;       ///< a view starts this far from the camera
  double depth_max_m = 5.0;       ///< measurements farther away are not integrated
  /// A zero crossing counts as a surface only where the fused weight (frames that saw it) is
  /// above this (raycast and mesh extraction both; 0.5 accepts a surface seen once).
  double weight_threshold = 0.5;
  /// Surface "raycast" only. Raycast cracks: Open3D's raycast leaves thin lines without a hit where the surface was
  /// observed (along the silhouettes of objects in the frames that were fused). A pixel without a
  /// hit whose valid 8-neighbours (at least 3) agree within 5 % is marched along its own ray
  /// through their depth range (with refine_hits; else, or where that finds no crossing, it takes
  /// their mean depth) and takes their mean normal and colour, repeated this many passes (0 = off).
  int crack_fill_passes = 2;
  /// Surface "raycast" only: move each hit onto the zero crossing of the trilinearly read TSDF (TsdfField;
  /// Open3D's own crossing comes from nearest-voxel values and is off by up to a voxel along the
  /// ray). false = Open3D's depth as it is.
  bool refine_hits = true;
  /// How a view finds the surface: "mesh" (SurfaceMesh: the TSDF's marching-cubes mesh, extracted
  /// once after each change of the volume, z-buffered per view; refine_hits and crack_fill_passes
  /// do not apply: its vertices lie on the trilinear crossing along voxel edges and it has no
  /// cracks) or "raycast" (Open3D's RayCast with refine_hits and the crack fill). The mesh is the
  /// default: 2-4x faster per view, better on the small office and study-room, 0.29 dB worse on
  /// two settings of the specular large office (docs/RESULTS.md "A mesh instead of a raycast");
  /// the raycast costs nothing after an Integrate, the mesh an extraction (~0.8 s for a room)
  /// before the next view.
  std::string surface = "mesh";
  /// OpenMP threads of Open3D's kernels (set in the calling thread before each call).
  int threads = 1;
  /// Who integrates a frame into the touched blocks: "p2i" (fusion/tsdf_integrate.h, the
  /// default: Open3D 0.16's arithmetic, float for float, in less than half its time) or
  /// "open3d" (VoxelBlockGrid::Integrate itself, the reference). The blocks a frame touches are
  /// Open3D's choice either way.
  std::string integrator = "p2i";
  /// Reads the keys present in a YAML map (others keep their defaults), then Validate().
  /// Unknown keys and bad values throw std::runtime_error naming `source`, the line and the key.
  static TsdfOptions FromYaml(const YAML::Node& node, const std::string& source);
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
  /// These options with block_resolution auto (0) resolved for frames of `frames` (8 or 16, as
  /// above); an explicit block_resolution is kept.
  TsdfOptions ForFrames(const scene::CameraInfo& frames) const;
  /// What auto chose and why, for logs: "blocks auto: 8^3 voxels (a frame pixel is 1.9 cm wide at
  /// 5 m, a voxel 2 cm)".
  std::string DescribeBlockChoice(const scene::CameraInfo& frames) const;
};

/// Depth, normals and voxel colour raycast from the TSDF at one pose.
struct TsdfRaycast {
  cv::Mat depth;    ///< CV_32FC1 z-depth (m) along the optical axis, 0 = no surface
  cv::Mat normals;  ///< CV_32FC3 unit normals in the camera frame, facing the camera; 0 = none
  cv::Mat colour;   ///< CV_32FC3 RGB in [0, 1] (interpolated voxel colour); 0 = none
};

struct TsdfStats {
  int64_t frames = 0;        ///< frames integrated
  int64_t blocks = 0;        ///< allocated voxel blocks
  double memory_bytes = 0;   ///< bytes of voxel data (tsdf + weight + colour, float32) + keys
  /// Blocks the hash map has room for (Open3D allocates, and touches, the voxel data of all of
  /// them: the process's memory follows this, not `blocks`); it doubles when the blocks fill it.
  int64_t capacity_blocks = 0;
  double block_volume_m3 = 0;  ///< volume of the allocated blocks (m^3)
};

/// Thread-compatible: one caller at a time (Integrate and Raycast both touch Open3D's hash map).
/// Frames are integrated as they arrive (incremental: Raycast works between any two Integrate
/// calls).
class TsdfVolume {
 public:
  /// `options.block_resolution` must be resolved (TsdfOptions::ForFrames): auto (0) throws
  /// std::invalid_argument, as bad options do.
  explicit TsdfVolume(TsdfOptions options);
  ~TsdfVolume();
  TsdfVolume(TsdfVolume&&) noexcept;
  TsdfVolume& operator=(TsdfVolume&&) noexcept;
  /// A deep copy of the voxel data and frame count (the copy's mesh is built on its first use).
  TsdfVolume Clone() const;

  /// Fuses one frame (rgb CV_8UC3 RGB, depth CV_32FC1 metres, 0 = invalid, both of `camera`'s
  /// size; `frame.pose` camera-to-world). Throws std::invalid_argument naming the frame on a
  /// wrong size or type.
  void Integrate(const scene::RgbdSample& frame, const scene::CameraInfo& camera);

  /// Raycasts the fused surface seen from `pose` through `camera` (any size and intrinsics).
  /// An empty volume gives all-zero maps. `only` (optional, CV_8UC1 of the camera's size): the
  /// pixels wanted (non-zero); the others may be 0. Surface "mesh" then draws only those (its cost
  /// follows them); surface "raycast" casts every ray.
  TsdfRaycast Raycast(const scene::Pose& pose, const scene::CameraInfo& camera,
                      const cv::Mat* only = nullptr);

  /// Builds what Raycast reuses between changes of the volume (the mesh of surface "mesh", the
  /// trilinear field of refine_hits) now, so a caller that loads a volume in the background pays
  /// for it there instead of in its first view. Optional.
  void Prepare();

  TsdfStats Stats() const;
  const TsdfOptions& options() const { return options_; }

  /// Writes the voxel data (Open3D .npz) atomically: `path` + ".tmp" then rename.
  void Save(const std::string& path) const;
  /// Reads a volume written by Save. `options` must hold the voxel size and block resolution it
  /// was saved with (the caller stores them beside it). Throws std::runtime_error naming the file.
  static TsdfVolume Load(const std::string& path, TsdfOptions options);

 private:
  /// Options checked, no grid allocated yet: Clone and Load put theirs in.
  struct Unallocated {};
  TsdfVolume(TsdfOptions options, Unallocated);
  struct Impl;
  TsdfOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace p2i::fusion
