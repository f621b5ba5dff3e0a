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

}  // namespace

/// A vertex in one view: screen position (pixels) and depth (not in the anonymous namespace:
/// SurfaceMesh::View, a member type, holds them).
struct ViewVertex {
  float x, y, z;
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

  // Each chunk's own vertices (a vertex shared by chunks is copied into each).
  std::vector<int32_t> seen_in(nv, -1), local_index(nv, 0);
  chunks_.reserve(members.size());
  for (size_t ci = 0; ci < members.size(); ++ci) {
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
    Eigen::Vector3f lo = pos_[ch.vertex_begin], hi = lo;
    for (int64_t v = ch.vertex_begin; v < ch.vertex_end; ++v) {
      lo = lo.cwiseMin(pos_[v]);
      hi = hi.cwiseMax(pos_[v]);
    }
    ch.centre = 0.5f * (lo + hi);
    ch.radius = 0.5f * (hi - lo).norm();
    chunks_.push_back(ch);
  }
}

/// One view: the camera, the chunks it can see with their vertices in it, the z-buffer.
struct SurfaceMesh::View {
  Eigen::Matrix3f r;  // world -> camera
  Eigen::Vector3f t;
  float fx, fy, cx, cy, depth_min, depth_max;
  int w, h;
  std::vector<int32_t> visible;  // chunk indices
  std::vector<int64_t> offset;   // chunk -> its first vertex in `verts` (-1 = not visible)
  std::vector<ViewVertex> verts;
  std::vector<float> zbuf;       // nearest front-face depth per pixel
  std::vector<int64_t> id;       // its triangle: chunk << 32 | triangle in chunk; -1 = none
  const uint8_t* only = nullptr;  // pixels to draw (non-zero), row stride w; null = all
  cv::Mat only_sum;              // integral image of `only` != 0 (CV_32S, (h + 1) x (w + 1))

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
  CullAndTransform(&view);
  DrawFrontFaces(&view);
  Resolve(view, out);
}

// Chunks whose bounding sphere can reach into the frustum, their vertices in the view.
void SurfaceMesh::CullAndTransform(View* view) const {
  View& v = *view;
  v.offset.assign(chunks_.size(), -1);
  for (size_t ci = 0; ci < chunks_.size(); ++ci) {
    const Chunk& ch = chunks_[ci];
    const Eigen::Vector3f centre = v.r * ch.centre + v.t;
    if (!SphereMayBeInView(centre, ch.radius, v.depth_min, v.depth_max, v.fx, v.fy, v.cx, v.cy, v.w, v.h))
      continue;
    if (v.only != nullptr) {
      int u0, u1, v0, v1;
      SphereScreenBox(centre, ch.radius, v.fx, v.fy, v.cx, v.cy, v.w, v.h, &u0, &u1, &v0, &v1);
      if (!v.AnyToDraw(u0, u1, v0, v1)) continue;
    }
    v.offset[ci] = static_cast<int64_t>(v.verts.size());
    v.visible.push_back(static_cast<int32_t>(ci));
    for (int64_t i = ch.vertex_begin; i < ch.vertex_end; ++i) {
      const Eigen::Vector3f p = v.r * pos_[i] + v.t;
      const float iz = p.z() > 0.0f ? 1.0f / p.z() : 0.0f;
      v.verts.push_back({v.fx * p.x() * iz + v.cx, v.fy * p.y() * iz + v.cy, p.z()});
    }
  }
}

// Z-buffer of front faces: the nearest triangle at each pixel centre.
void SurfaceMesh::DrawFrontFaces(View* view) const {
  View& vw = *view;
  const int w = vw.w, h = vw.h;
  vw.zbuf.assign(static_cast<size_t>(w) * h, std::numeric_limits<float>::infinity());
  vw.id.assign(static_cast<size_t>(w) * h, -1);
  for (int32_t ci : vw.visible) {
    const Chunk& ch = chunks_[static_cast<size_t>(ci)];
    const ViewVertex* vv = vw.verts.data() + vw.offset[static_cast<size_t>(ci)];
    for (int64_t tr = ch.triangle_begin; tr < ch.triangle_end; ++tr) {
      const ViewVertex& a = vv[tri_[3 * tr]];
      const ViewVertex& b = vv[tri_[3 * tr + 1]];
      const ViewVertex& c = vv[tri_[3 * tr + 2]];
      if (a.z < vw.depth_min || b.z < vw.depth_min || c.z < vw.depth_min) continue;
      const float area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
      // Front faces have winding_ * area < 0 (see the header of winding_): the normal's side.
      if (!(winding_ * area < 0.0f)) continue;
      const int u0 = std::max(0, static_cast<int>(std::ceil(std::min({a.x, b.x, c.x}))));
      const int u1 = std::min(w - 1, static_cast<int>(std::floor(std::max({a.x, b.x, c.x}))));
      if (u0 > u1) continue;
      const int v0 = std::max(0, static_cast<int>(std::ceil(std::min({a.y, b.y, c.y}))));
      const int v1 = std::min(h - 1, static_cast<int>(std::floor(std::max({a.y, b.y, c.y}))));
      if (v0 > v1) continue;
      if (!vw.AnyToDraw(u0, u1, v0, v1)) continue;
      const float s = area > 0.0f ? 1.0f : -1.0f, inv_area = 1.0f / std::fabs(area);
      const float iza = 1.0f / a.z, izb = 1.0f / b.z, izc = 1.0f / c.z;
      const int64_t tag = (static_cast<int64_t>(ci) << 32) | (tr - ch.triangle_begin);
      for (int v = v0; v <= v1; ++v) {
        const float py = static_cast<float>(v);
        for (int u = u0; u <= u1; ++u) {
          const float px = static_cast<float>(u);
          // Edge functions, non-negative inside (inclusive: a pixel on a shared edge is tested
          // by both triangles, so no crack opens between them).
          const float e0 = s * ((c.x - b.x) * (py - b.y) - (c.y - b.y) * (px - b.x));
          const float e1 = s * ((a.x - c.x) * (py - c.y) - (a.y - c.y) * (px - c.x));
          const float e2 = s * ((b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x));
          if (e0 < 0.0f || e1 < 0.0f || e2 < 0.0f) continue;
          const float iz = (e0 * iza + e1 * izb + e2 * izc) * inv_area;
          if (!(iz > 0.0f)) continue;
          const float z = 1.0f / iz;
          const size_t i = static_cast<size_t>(v) * w + u;
          if (vw.only != nullptr && vw.only[i] == 0) continue;
          if (z < vw.zbuf[i] && z <= vw.depth_max) {
            vw.zbuf[i] = z;
            vw.id[i] = tag;
          }
        }
      }
    }
  }
}

// Perspective-correct barycentrics of each pixel's triangle give its normal and colour.
void SurfaceMesh::Resolve(const View& vw, TsdfRaycast* out) const {
  for (int v = 0; v < vw.h; ++v) {
    float* drow = out->depth.ptr<float>(v);
    cv::Vec3f* nrow = out->normals.ptr<cv::Vec3f>(v);
    cv::Vec3f* crow = out->colour.ptr<cv::Vec3f>(v);
    for (int u = 0; u < vw.w; ++u) {
      const size_t i = static_cast<size_t>(v) * vw.w + u;
      if (vw.id[i] < 0) continue;
      const size_t ci = static_cast<size_t>(vw.id[i] >> 32);
      const Chunk& ch = chunks_[ci];
      const int64_t tr = ch.triangle_begin + (vw.id[i] & 0xffffffff);
      const ViewVertex* vv = vw.verts.data() + vw.offset[ci];
      const int32_t ia = tri_[3 * tr], ib = tri_[3 * tr + 1], ic = tri_[3 * tr + 2];
      const ViewVertex &a = vv[ia], &b = vv[ib], &c = vv[ic];
      const float px = static_cast<float>(u), py = static_cast<float>(v);
      const float e0 = std::fabs((c.x - b.x) * (py - b.y) - (c.y - b.y) * (px - b.x));
      const float e1 = std::fabs((a.x - c.x) * (py - c.y) - (a.y - c.y) * (px - c.x));
      const float e2 = std::fabs((b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x));
      const float q0 = e0 / a.z, q1 = e1 / b.z, q2 = e2 / c.z, q = q0 + q1 + q2;
      if (!(q > 0.0f)) continue;
      const float b0 = q0 / q, b1 = q1 / q, b2 = q2 / q;
      const int64_t va = ch.vertex_begin + ia, vb = ch.vertex_begin + ib, vc = ch.vertex_begin + ic;
      const Shading &sa = shade_[va], &sb = shade_[vb], &sc = shade_[vc];
      Eigen::Vector3f n = vw.r * (b0 * sa.nrm + b1 * sb.nrm + b2 * sc.nrm);
      const float len = n.norm();
      if (!(len > 1e-6f)) continue;
      n /= len;
      const Eigen::Vector3f ray((px - vw.cx) / vw.fx, (py - vw.cy) / vw.fy, 1.0f);
      if (n.dot(ray) > 0.0f) n = -n;
      const Eigen::Vector3f col = (b0 * sa.col + b1 * sb.col + b2 * sc.col).cwiseMax(0.0f).cwiseMin(1.0f);
      drow[u] = vw.zbuf[i];
      nrow[u] = cv::Vec3f(n.x(), n.y(), n.z());
      crow[u] = cv::Vec3f(col.x(), col.y(), col.z());
    }
  }
}

}  // namespace p2i::fusion
