/// @file surface_mesh.h
/// @brief The fused surface as a triangle mesh (marching cubes of the TSDF, extracted once per
/// change of the volume) and its rasterisation at any pose and camera: the `mesh` surface of
/// TsdfOptions, the same depth, normals and voxel colour maps as the raycast at a fraction of
/// its cost per view.
///
/// Why: a raycast pays per pixel for a march through the voxel hash map (Open3D's RayCast plus
/// our trilinear hit refinement: ~16 ms at 128x128 and ~60 ms at 320x240 on one thread, where the
/// whole view's budget is 10 and 33 ms). The mesh's vertices already sit on the trilinear zero
/// crossing along the voxel edges, so a z-buffer over its triangles gives the surface without a
/// march. No Open3D type here: TsdfVolume hands over plain arrays.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "fusion/tsdf_volume.h"
#include "scene/camera_info.h"
#include "scene/pose.h"

namespace p2i::fusion {

struct ViewVertex;  // a vertex projected into one view (surface_mesh.cc)

/// A triangle mesh in world coordinates, grouped into cubic chunks (each with its own vertices,
/// duplicated where triangles of two chunks share one) so a view transforms and rasterises only
/// the chunks its frustum can see. Within a chunk, triangles are ordered along a space-filling
/// curve and cut into clusters of up to 64 neighbouring triangles, each with a bounding sphere: a
/// view skips the clusters outside its frustum (or over no pixel it must draw) without testing
/// their triangles one by one.
class SurfaceMesh {
 public:
  /// `positions`, `normals` (unit, pointing to free space: the TSDF's positive side) and `colours`
  /// (RGB in [0, 1]) per vertex, three vertex indices per triangle. `chunk_m`: edge of a chunk.
  /// Throws std::invalid_argument when the arrays disagree in size or an index is out of range.
  SurfaceMesh(const std::vector<Eigen::Vector3f>& positions, const std::vector<Eigen::Vector3f>& normals,
              const std::vector<Eigen::Vector3f>& colours, const std::vector<int64_t>& triangles,
              float chunk_m = 0.5f);

  /// Depth (z along the optical axis), unit normals in the camera frame facing the camera and
  /// colour at every pixel centre whose ray meets a front face (a face whose normal points to the
  /// camera, as a raycast only meets the TSDF going from its positive to its negative side) with
  /// depth in [depth_min, depth_max]; 0 elsewhere. Triangles with a vertex nearer than depth_min
  /// are skipped (not clipped). `out`'s maps are allocated here.
  /// `only` (optional, CV_8UC1 of the camera's size): draw only the pixels where it is non-zero;
  /// the others stay 0, and chunks and triangles whose screen box holds none of them are skipped
  /// (filling the pixels another surface left empty costs what those pixels need, not a view).
  void Rasterize(const scene::Pose& pose, const scene::CameraInfo& camera, float depth_min,
                 float depth_max, TsdfRaycast* out, const cv::Mat* only = nullptr) const;

  int64_t triangles() const { return triangle_count_; }
  int64_t vertices() const { return static_cast<int64_t>(pos_.size()); }
  int64_t chunks() const { return static_cast<int64_t>(chunks_.size()); }

 private:
  struct View;  // one Rasterize call's camera, visible chunks and buffers (surface_mesh.cc)
  struct Chunk;
  struct Cluster;
  /// Orders one chunk's triangles (indices into `triangles`) along a Morton curve of their centroids.
  static void SortAlongCurve(const std::vector<Eigen::Vector3f>& positions, const std::vector<int64_t>& triangles,
                             std::vector<int64_t>* members);
  void AddClusters(Chunk* ch);  ///< cuts the chunk's triangles (already in tri_) into clusters
  void CullAndTransform(View* view) const;
  void DrawFrontFaces(View* view) const;
  void DrawCluster(const Chunk& ch, const Cluster& cl, const ViewVertex* vv, View* view) const;
  void DrawTriangle(int64_t vertex_begin, const int32_t* t, const ViewVertex* vv, float area, int u0, int u1,
                    int v0, int v1, View* view) const;

  struct Chunk {
    Eigen::Vector3f centre;
    float radius = 0.0f;           ///< bounding sphere of its vertices
    int64_t vertex_begin = 0, vertex_end = 0;      ///< into pos_ / shade_
    int64_t triangle_begin = 0, triangle_end = 0;  ///< into tri_ (local vertex indices per chunk)
    int64_t cluster_begin = 0, cluster_end = 0;    ///< into clusters_
  };
  /// Consecutive triangles of one chunk, [begin, end) relative to its triangle_begin, and the
  /// bounding sphere of their vertices.
  struct Cluster {
    Eigen::Vector3f centre;
    float radius = 0.0f;
    int32_t begin = 0, end = 0;
  };
  std::vector<Chunk> chunks_;
  std::vector<Cluster> clusters_;
  std::vector<Eigen::Vector3f> pos_;  ///< read per vertex of a visible chunk (CullAndTransform)
  /// Normal and colour of each vertex side by side: DrawTriangle reads both for its 3 vertices,
  /// from one cache line each rather than two.
  struct Shading {
    Eigen::Vector3f nrm, col;
  };
  std::vector<Shading> shade_;
  std::vector<int32_t> tri_;  ///< 3 per triangle, indices relative to the chunk's vertex_begin
  int64_t triangle_count_ = 0;
  /// +1 when a counter-clockwise (right-handed) triangle's cross product points along its vertex
  /// normals (to free space), -1 when against; marching cubes winds all triangles one way.
  float winding_ = 1.0f;
};

}  // namespace p2i::fusion
