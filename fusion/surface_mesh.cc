/// @file surface_mesh.cc
/// @brief Chunked triangle mesh and its z-buffer rasteriser (pixel centres at integer
/// coordinates, as Open3D's raycast and p2i's cameras have them).
#include "fusion/surface_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include <opencv2/imgproc.hpp>

#include "fusion/frustum.h"

namespace p2i::fusion {
namespace {

int64_t ChunkKey(const Eigen::Vector3f& p, float chunk_m) {
  const auto c = [&](float x) { return static_cast<int64_t>(std::floor(x / chunk_m)) + (int64_t{1} << 20); };
  return (c(p.x()) << 42) | (c(p.y()) << 21) | c(p.z());
}

constexpr int kClusterTriangles = 64;

/// Position along a Morton (Z-order) curve of a point with coordinates in [0, 1]^3, 10 bits each:
/// sorting by it keeps neighbours in space near each other in the order.
uint32_t MortonCode(const Eigen::Vector3f& unit) {
  const auto spread = [](float x) {
    uint32_t v = static_cast<uint32_t>(std::min(std::max(x, 0.0f), 1.0f) * 1023.0f);
    v = (v | (v << 16)) & 0x030000FFu;
    v = (v | (v << 8)) & 0x0300F00Fu;
    v = (v | (v << 4)) & 0x030C30C3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
  };
  return (spread(unit.x()) << 2) | (spread(unit.y()) << 1) | spread(unit.z());
}

/// Axis-aligned box of the points [begin, end) (not empty).
template <typename It>
void BoxOf(It begin, It end, Eigen::Vector3f* lo, Eigen::Vector3f* hi) {
  *lo = *hi = *begin;
  for (It p = begin; p != end; ++p) {
    *lo = lo->cwiseMin(*p);
    *hi = hi->cwiseMax(*p);
  }
}

/// Bounding sphere (centre of the box, half its diagonal) of the points [begin, end).
template <typename It>
void BoundingSphere(It begin, It end, Eigen::Vector3f* centre, float* radius) {
  Eigen::Vector3f lo, hi;
  BoxOf(begin, end, &lo, &hi);
  *centre = 0.5f * (lo + hi);
  *radius = 0.5f * (hi - lo).norm();
}

}  // namespace

/// A vertex in one view: screen position (pixels), depth and its inverse (not in the anonymous namespace:
/// SurfaceMesh::View, a member type, holds them).
struct ViewVertex {
  float x, y, z;
  float iz;  ///< 1 / z where z > 0, else 0
};

SurfaceMesh::SurfaceMesh(const std::vector<Eigen::Vector3f>& positions,
                         const std::vector<Eigen::Vector3f>& normals,
                         const std::vector<Eigen::Vector3f>& colours, const std::vector<int64_t>& triangles,
                         float chunk_m) {
  const size_t nv = positions.size();
  if (normals.size() != nv || colours.size() != nv)
    throw std::invalid_argument("SurfaceMesh: " + std::to_string(nv) + " positions but " +
                                std::to_string(normals.size()) + " normals and " +
                                std::to_string(colours.size()) + " colours");
  if (triangles.size() % 3 != 0)
    throw std::invalid_argument("SurfaceMesh: triangle indices must come in threes, got " +
                                std::to_string(triangles.size()));
  if (!(chunk_m > 0.0f)) throw std::invalid_argument("SurfaceMesh: chunk_m must be > 0");
  for (int64_t i : triangles)
    if (i < 0 || i >= static_cast<int64_t>(nv))
      throw std::invalid_argument("SurfaceMesh: triangle index " + std::to_string(i) +
                                  " out of range (" + std::to_string(nv) + " vertices)");
  const int64_t nt = static_cast<int64_t>(triangles.size() / 3);
  triangle_count_ = nt;

  // Triangles per chunk (by centroid), and the winding that agrees with the vertex normals.
  std::unordered_map<int64_t, int32_t> chunk_of_key;
  std::vector<std::vector<int64_t>> members;
  double agree = 0.0;
  for (int64_t t = 0; t < nt; ++t) {
    const Eigen::Vector3f& a = positions[triangles[3 * t]];
    const Eigen::Vector3f& b = positions[triangles[3 * t + 1]];
    const Eigen::Vector3f& c = positions[triangles[3 * t + 2]];
    const Eigen::Vector3f n = normals[triangles[3 * t]] + normals[triangles[3 * t + 1]] + normals[triangles[3 * t + 2]];
    agree += (b - a).cross(c - a).dot(n) >= 0.0f ? 1.0 : -1.0;
    const auto [it, added] =
        chunk_of_key.emplace(ChunkKey((a + b + c) / 3.0f, chunk_m), static_cast<int32_t>(members.size()));
    if (added) members.emplace_back();
    members[static_cast<size_t>(it->second)].push_back(t);
  }
  winding_ = agree >= 0.0 ? 1.0f : -1.0f;

  // Each chunk's own vertices (a vertex shared by chunks is copied into each), its triangles in
  // Morton order of their centroids, cut into clusters.
  std::vector<int32_t> seen_in(nv, -1), local_index(nv, 0);
  chunks_.reserve(members.size());
  for (size_t ci = 0; ci < members.size(); ++ci) {
    SortAlongCurve(positions, triangles, &members[ci]);
    Chunk ch;
    ch.vertex_begin = static_cast<int64_t>(pos_.size());
    ch.triangle_begin = static_cast<int64_t>(tri_.size() / 3);
    for (int64_t t : members[ci]) {
      for (int k = 0; k < 3; ++k) {
        const int64_t g = triangles[3 * t + k];
        if (seen_in[g] != static_cast<int32_t>(ci)) {
          seen_in[g] = static_cast<int32_t>(ci);
          local_index[g] = static_cast<int32_t>(static_cast<int64_t>(pos_.size()) - ch.vertex_begin);
          pos_.push_back(positions[g]);
          shade_.push_back({normals[g], colours[g]});
        }
        tri_.push_back(local_index[g]);
      }
    }
    ch.vertex_end = static_cast<int64_t>(pos_.size());
    ch.triangle_end = static_cast<int64_t>(tri_.size() / 3);
    BoundingSphere(pos_.begin() + ch.vertex_begin, pos_.begin() + ch.vertex_end, &ch.centre, &ch.radius);
    AddClusters(&ch);
    chunks_.push_back(ch);
  }
}

void SurfaceMesh::SortAlongCurve(const std::vector<Eigen::Vector3f>& positions,
                                 const std::vector<int64_t>& triangles, std::vector<int64_t>* members) {
  std::vector<Eigen::Vector3f> centroid;
  centroid.reserve(members->size());
  for (int64_t t : *members)
    centroid.push_back((positions[triangles[3 * t]] + positions[triangles[3 * t + 1]] +
                        positions[triangles[3 * t + 2]]) / 3.0f);
  Eigen::Vector3f lo, hi;
  BoxOf(centroid.begin(), centroid.end(), &lo, &hi);
  const float extent = std::max((hi - lo).maxCoeff(), 1e-6f);  // one scale: keeps the cells cubic
  std::vector<std::pair<uint32_t, int64_t>> keyed;
  keyed.reserve(members->size());
  for (size_t i = 0; i < members->size(); ++i)
    keyed.emplace_back(MortonCode((centroid[i] - lo) / extent), (*members)[i]);
  std::stable_sort(keyed.begin(), keyed.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  for (size_t i = 0; i < keyed.size(); ++i) (*members)[i] = keyed[i].second;
}

void SurfaceMesh::AddClusters(Chunk* ch) {
  ch->cluster_begin = static_cast<int64_t>(clusters_.size());
  const int64_t n = ch->triangle_end - ch->triangle_begin;
  std::vector<Eigen::Vector3f> points;
  for (int64_t begin = 0; begin < n; begin += kClusterTriangles) {
    Cluster cl;
    cl.begin = static_cast<int32_t>(begin);
    cl.end = static_cast<int32_t>(std::min<int64_t>(n, begin + kClusterTriangles));
    points.clear();
    for (int64_t k = 3 * (ch->triangle_begin + cl.begin); k < 3 * (ch->triangle_begin + cl.end); ++k)
      points.push_back(pos_[static_cast<size_t>(ch->vertex_begin + tri_[static_cast<size_t>(k)])]);
    BoundingSphere(points.begin(), points.end(), &cl.centre, &cl.radius);
    clusters_.push_back(cl);
  }
  ch->cluster_end = static_cast<int64_t>(clusters_.size());
}

/// One view: the camera, the chunks it can see with their vertices in it, the z-buffer and the
/// maps it writes.
struct SurfaceMesh::View {
  Eigen::Matrix3f r;  // world -> camera
  Eigen::Vector3f t;
  float fx, fy, cx, cy, depth_min, depth_max;
  int w, h;
  std::vector<int32_t> visible;  // chunk indices
  std::vector<int64_t> offset;   // chunk -> its first vertex in `verts` (-1 = not visible)
  std::vector<ViewVertex> verts;
  std::vector<float> zbuf;       // nearest front-face depth per pixel
  float* depth = nullptr;        // the output maps (continuous, w x h): written per pixel whenever
  cv::Vec3f* normals = nullptr;  // a nearer front face is found there
  cv::Vec3f* colour = nullptr;
  const uint8_t* only = nullptr;  // pixels to draw (non-zero), row stride w; null = all
  cv::Mat only_sum;              // integral image of `only` != 0 (CV_32S, (h + 1) x (w + 1))

  /// Whether a sphere (world frame) can reach into the view and over a pixel to draw.
  bool MayDraw(const Eigen::Vector3f& world_centre, float radius) const {
    const Eigen::Vector3f centre = r * world_centre + t;
    if (!SphereMayBeInView(centre, radius, depth_min, depth_max, fx, fy, cx, cy, w, h)) return false;
    if (only == nullptr) return true;
    int u0, u1, v0, v1;
    SphereScreenBox(centre, radius, fx, fy, cx, cy, w, h, &u0, &u1, &v0, &v1);
    return AnyToDraw(u0, u1, v0, v1);
  }

  /// Whether the box [u0, u1] x [v0, v1] (inside the image) holds a pixel to draw.
  bool AnyToDraw(int u0, int u1, int v0, int v1) const {
    if (only == nullptr) return true;
    const int* top = only_sum.ptr<int>(v0);
    const int* bottom = only_sum.ptr<int>(v1 + 1);
    return bottom[u1 + 1] - bottom[u0] - top[u1 + 1] + top[u0] > 0;
  }
};

void SurfaceMesh::Rasterize(const scene::Pose& pose, const scene::CameraInfo& camera, float depth_min,
                            float depth_max, TsdfRaycast* out, const cv::Mat* only) const {
  const int w = camera.image_width, h = camera.image_height;
  out->depth = cv::Mat::zeros(h, w, CV_32FC1);
  out->normals = cv::Mat::zeros(h, w, CV_32FC3);
  out->colour = cv::Mat::zeros(h, w, CV_32FC3);
  if (w <= 0 || h <= 0) return;
  // One View per thread, kept between calls: its buffers (the visible chunks' vertices, the
  // z-buffer) keep their capacity, so a view neither reallocates them nor faults in fresh pages.
  thread_local View view;
  view.visible.clear();
  view.verts.clear();
  view.only = nullptr;
  cv::Mat only_bytes;
  if (only != nullptr) {
    if (only->type() != CV_8UC1 || only->cols != w || only->rows != h)
      throw std::invalid_argument("SurfaceMesh::Rasterize: the mask of pixels to draw must be CV_8UC1 " +
                                  std::to_string(w) + "x" + std::to_string(h) + ", got type " +
                                  std::to_string(only->type()) + " " + std::to_string(only->cols) + "x" +
                                  std::to_string(only->rows));
    only_bytes = only->isContinuous() ? *only : only->clone();
    cv::integral((only_bytes != 0) / 255, view.only_sum, CV_32S);  // 1 per pixel to draw
    if (view.only_sum.at<int>(h, w) == 0) return;
    view.only = only_bytes.ptr<uint8_t>(0);
  }
  const Eigen::Matrix4d cw = pose.Inverse().ToMatrix();
  view.r = cw.block<3, 3>(0, 0).cast<float>();
  view.t = cw.block<3, 1>(0, 3).cast<float>();
  view.fx = static_cast<float>(camera.fx()), view.fy = static_cast<float>(camera.fy());
  view.cx = static_cast<float>(camera.cx()), view.cy = static_cast<float>(camera.cy());
  view.depth_min = depth_min, view.depth_max = depth_max;
  view.w = w, view.h = h;
  view.depth = out->depth.ptr<float>(0);
  view.normals = out->normals.ptr<cv::Vec3f>(0);
  view.colour = out->colour.ptr<cv::Vec3f>(0);
  CullAndTransform(&view);
  DrawFrontFaces(&view);
}

// Chunks whose bounding sphere can reach into the frustum, their vertices in the view.
void SurfaceMesh::CullAndTransform(View* view) const {
  View& v = *view;
  v.offset.assign(chunks_.size(), -1);
  for (size_t ci = 0; ci < chunks_.size(); ++ci) {
    const Chunk& ch = chunks_[ci];
    if (!v.MayDraw(ch.centre, ch.radius)) continue;
    v.offset[ci] = static_cast<int64_t>(v.verts.size());
    v.visible.push_back(static_cast<int32_t>(ci));
    for (int64_t i = ch.vertex_begin; i < ch.vertex_end; ++i) {
      const Eigen::Vector3f p = v.r * pos_[i] + v.t;
      const float iz = p.z() > 0.0f ? 1.0f / p.z() : 0.0f;
      v.verts.push_back({v.fx * p.x() * iz + v.cx, v.fy * p.y() * iz + v.cy, p.z(), iz});
    }
  }
}

namespace {

/// ceil(x) for x in [0, INT_MAX): the conversion truncates towards zero, which is floor there.
inline int CeilNonNegative(float x) {
  const int t = static_cast<int>(x);
  return t + (static_cast<float>(t) < x ? 1 : 0);
}

}  // namespace

// Z-buffer of front faces: the nearest triangle at each pixel centre, cluster by cluster of the
// visible chunks.
void SurfaceMesh::DrawFrontFaces(View* view) const {
  View& vw = *view;
  const int w = vw.w, h = vw.h;
  vw.zbuf.assign(static_cast<size_t>(w) * h, std::numeric_limits<float>::infinity());
  for (int32_t ci : vw.visible) {
    const Chunk& ch = chunks_[static_cast<size_t>(ci)];
    const ViewVertex* vv = vw.verts.data() + vw.offset[static_cast<size_t>(ci)];
    for (int64_t i = ch.cluster_begin; i < ch.cluster_end; ++i) {
      const Cluster& cl = clusters_[static_cast<size_t>(i)];
      if (vw.MayDraw(cl.centre, cl.radius)) DrawCluster(ch, cl, vv, view);
    }
  }
}

// One cluster's triangles: most of them cover no pixel centre or lie outside the image at the
// resolutions views are asked for, so the loop rejects by pixel box first, before any other test.
void SurfaceMesh::DrawCluster(const Chunk& ch, const Cluster& cl, const ViewVertex* vv, View* view) const {
  View& vw = *view;
  const int w = vw.w;
  const float u_max = static_cast<float>(w - 1), v_max = static_cast<float>(vw.h - 1);
  const int32_t* t = tri_.data() + 3 * (ch.triangle_begin + cl.begin);
  for (int64_t k = cl.begin; k < cl.end; ++k, t += 3) {
    const ViewVertex& a = vv[t[0]];
    const ViewVertex& b = vv[t[1]];
    const ViewVertex& c = vv[t[2]];
    // Pixel box: ceil of the smallest coordinate to floor of the largest, inside the image
    // (written so a NaN coordinate rejects the triangle).
    const float x0 = std::max(std::min(std::min(a.x, b.x), c.x), 0.0f);
    const float x1 = std::min(std::max(std::max(a.x, b.x), c.x), u_max);
    if (!(x0 <= x1)) continue;
    const int u0 = CeilNonNegative(x0), u1 = static_cast<int>(x1);
    if (u0 > u1) continue;
    const float y0 = std::max(std::min(std::min(a.y, b.y), c.y), 0.0f);
    const float y1 = std::min(std::max(std::max(a.y, b.y), c.y), v_max);
    if (!(y0 <= y1)) continue;
    const int v0 = CeilNonNegative(y0), v1 = static_cast<int>(y1);
    if (v0 > v1) continue;
    if (a.z < vw.depth_min || b.z < vw.depth_min || c.z < vw.depth_min) continue;
    const float area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    // Front faces have winding_ * area < 0 (see the header of winding_): the normal's side.
    if (!(winding_ * area < 0.0f)) continue;
    if (!vw.AnyToDraw(u0, u1, v0, v1)) continue;
    DrawTriangle(ch.vertex_begin, t, vv, area, u0, u1, v0, v1, view);
  }
}

// The pixel centres of one front face, [u0, u1] x [v0, v1] its pixel box (inside the image): where
// it is nearer than what the z-buffer holds, its depth, and normal and colour by
// perspective-correct barycentrics (forward shading: the triangle's vertices are in cache now, not
// when a later pass would look them up per pixel). Edge functions are non-negative inside
// (inclusive: a pixel on a shared edge is tested by both triangles, so no crack opens between
// them). Out of line: the triangle loop around it rejects most triangles and stays in registers.
__attribute__((noinline)) void SurfaceMesh::DrawTriangle(int64_t vertex_begin, const int32_t* t,
                                                         const ViewVertex* vv, float area, int u0, int u1,
                                                         int v0, int v1, View* view) const {
  View& vw = *view;
  const ViewVertex &a = vv[t[0]], &b = vv[t[1]], &c = vv[t[2]];
  const Shading &sa = shade_[static_cast<size_t>(vertex_begin + t[0])];
  const Shading &sb = shade_[static_cast<size_t>(vertex_begin + t[1])];
  const Shading &sc = shade_[static_cast<size_t>(vertex_begin + t[2])];
  const float s = area > 0.0f ? 1.0f : -1.0f, inv_area = 1.0f / std::fabs(area);
  for (int v = v0; v <= v1; ++v) {
    const float py = static_cast<float>(v);
    for (int u = u0; u <= u1; ++u) {
      const float px = static_cast<float>(u);
      const float e0 = s * ((c.x - b.x) * (py - b.y) - (c.y - b.y) * (px - b.x));
      const float e1 = s * ((a.x - c.x) * (py - c.y) - (a.y - c.y) * (px - c.x));
      const float e2 = s * ((b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x));
      if (e0 < 0.0f || e1 < 0.0f || e2 < 0.0f) continue;
      const float iz = (e0 * a.iz + e1 * b.iz + e2 * c.iz) * inv_area;
      if (!(iz > 0.0f)) continue;
      const float z = 1.0f / iz;
      const size_t i = static_cast<size_t>(v) * vw.w + u;
      if (vw.only != nullptr && vw.only[i] == 0) continue;
      if (!(z < vw.zbuf[i] && z <= vw.depth_max)) continue;
      vw.zbuf[i] = z;
      // The nearest face decides the pixel: where its shading is degenerate the pixel is empty.
      vw.depth[i] = 0.0f;
      vw.normals[i] = cv::Vec3f(0.0f, 0.0f, 0.0f);
      vw.colour[i] = cv::Vec3f(0.0f, 0.0f, 0.0f);
      const float q0 = e0 / a.z, q1 = e1 / b.z, q2 = e2 / c.z, q = q0 + q1 + q2;
      if (!(q > 0.0f)) continue;
      const float b0 = q0 / q, b1 = q1 / q, b2 = q2 / q;
      Eigen::Vector3f n = vw.r * (b0 * sa.nrm + b1 * sb.nrm + b2 * sc.nrm);
      const float len = n.norm();
      if (!(len > 1e-6f)) continue;
      n /= len;
      const Eigen::Vector3f ray((px - vw.cx) / vw.fx, (py - vw.cy) / vw.fy, 1.0f);
      if (n.dot(ray) > 0.0f) n = -n;
      const Eigen::Vector3f col = (b0 * sa.col + b1 * sb.col + b2 * sc.col).cwiseMax(0.0f).cwiseMin(1.0f);
      vw.depth[i] = z;
      vw.normals[i] = cv::Vec3f(n.x(), n.y(), n.z());
      vw.colour[i] = cv::Vec3f(col.x(), col.y(), col.z());
    }
  }
}

}  // namespace p2i::fusion
