/// @file surface_mesh_test.cc
/// @brief SurfaceMesh: the z-buffer gives exact depth, normals and colour of known triangles,
/// front faces only, no crack along shared edges, chunk and cluster culling lose nothing (against
/// a ray cast of every triangle), and a mask of pixels to draw gives exactly those pixels.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <catch2/catch.hpp>

#include "fusion/surface_mesh.h"
#include "tests/fusion/fusion_test_util.h"

namespace p2i::fusion {
namespace {

using testing::At;
using testing::Cam;

/// A grid of n x n quads (two triangles each) on the plane z = z0 over [-half, half]^2, normals
/// pointing to -z (towards a camera at the origin looking along +z) when `towards_origin`, else
/// +z; red varies with x. `flip_winding` turns every triangle's vertex order.
struct Grid {
  std::vector<Eigen::Vector3f> pos, nrm, col;
  std::vector<int64_t> tri;
};

Grid PlaneGrid(float z0, float half, int n, bool towards_origin, bool flip_winding) {
  Grid g;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const float x = -half + 2.0f * half * i / n, y = -half + 2.0f * half * j / n;
      g.pos.emplace_back(x, y, z0);
      g.nrm.emplace_back(0.0f, 0.0f, towards_origin ? -1.0f : 1.0f);
      g.col.emplace_back(0.5f + 0.4f * x / half, 0.2f, 0.8f);
    }
  auto idx = [&](int i, int j) { return static_cast<int64_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      std::vector<int64_t> t = {idx(i, j), idx(i + 1, j), idx(i + 1, j + 1),
                                idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)};
      if (flip_winding) {
        std::swap(t[1], t[2]);
        std::swap(t[4], t[5]);
      }
      g.tri.insert(g.tri.end(), t.begin(), t.end());
    }
  return g;
}

TEST_CASE("SurfaceMesh: a plane facing the camera is rasterised at its depth with no crack", "[unit]") {
  // Either winding: the rasteriser learns which way the triangles turn from their normals.
  const bool flip = GENERATE(false, true);
  const Grid g = PlaneGrid(2.0f, 3.0f, 37, /*towards_origin=*/true, flip);
  const SurfaceMesh mesh(g.pos, g.nrm, g.col, g.tri, 0.5f);
  CHECK(mesh.triangles() == 37 * 37 * 2);
  CHECK(mesh.chunks() > 1);
  const auto cam = Cam(64, 48, 50);
  TsdfRaycast r;
  mesh.Rasterize(At(0.03, -0.02, 0.0), cam, 0.1f, 5.0f, &r);
  REQUIRE(r.depth.size() == cv::Size(64, 48));
  // Every pixel hits (the plane fills the view; shared edges leave no crack), at z = 2.
  CHECK(cv::countNonZero(r.depth) == 64 * 48);
  double worst = 0.0;
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) worst = std::max(worst, std::abs(r.depth.at<float>(v, u) - 2.0));
  CHECK(worst < 1e-4);
  const cv::Vec3f n = r.normals.at<cv::Vec3f>(20, 30);
  CHECK(n[2] == Approx(-1.0f).margin(1e-5));
  // Colour: interpolated red = 0.5 + 0.4 x / 3 at the pixel's world x.
  const int u = 50, v = 10;
  const double x = 0.03 + (u - cam.cx()) / cam.fx() * 2.0;
  CHECK(r.colour.at<cv::Vec3f>(v, u)[0] == Approx(0.5 + 0.4 * x / 3.0).margin(1e-3));
  CHECK(r.colour.at<cv::Vec3f>(v, u)[2] == Approx(0.8).margin(1e-5));
}

TEST_CASE("SurfaceMesh: a face seen from behind is not drawn (as a TSDF raycast does not meet it)", "[unit]") {
  const Grid g = PlaneGrid(2.0f, 3.0f, 10, /*towards_origin=*/true, false);
  const SurfaceMesh mesh(g.pos, g.nrm, g.col, g.tri, 0.5f);
  const auto cam = Cam(32, 24, 25);
  TsdfRaycast front, behind;
  mesh.Rasterize(At(0, 0, 0), cam, 0.1f, 5.0f, &front);
  CHECK(cv::countNonZero(front.depth) == 32 * 24);
  // From z = 4 looking along -z (yawed 180 degrees) the plane's free side faces away.
  const scene::Pose back(Eigen::Vector3d(0, 0, 4), Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY())));
  mesh.Rasterize(back, cam, 0.1f, 5.0f, &behind);
  CHECK(cv::countNonZero(behind.depth) == 0);
  // The same plane with its normals turned is drawn from there and not from the origin.
  const Grid turned = PlaneGrid(2.0f, 3.0f, 10, /*towards_origin=*/false, false);
  const SurfaceMesh other(turned.pos, turned.nrm, turned.col, turned.tri, 0.5f);
  other.Rasterize(back, cam, 0.1f, 5.0f, &behind);
  other.Rasterize(At(0, 0, 0), cam, 0.1f, 5.0f, &front);
  CHECK(cv::countNonZero(behind.depth) == 32 * 24);
  CHECK(behind.depth.at<float>(12, 16) == Approx(2.0f).margin(1e-4));
  CHECK(cv::countNonZero(front.depth) == 0);
}

TEST_CASE("SurfaceMesh: the nearest front face wins, depth range and near triangles are honoured", "[unit]") {
  Grid g = PlaneGrid(3.0f, 5.0f, 8, true, false);
  const Grid near = PlaneGrid(1.5f, 0.3f, 4, true, false);
  const int64_t base = static_cast<int64_t>(g.pos.size());
  g.pos.insert(g.pos.end(), near.pos.begin(), near.pos.end());
  g.nrm.insert(g.nrm.end(), near.nrm.begin(), near.nrm.end());
  g.col.insert(g.col.end(), near.col.begin(), near.col.end());
  for (int64_t i : near.tri) g.tri.push_back(base + i);
  const auto cam = Cam(40, 40, 40);
  // One chunk or many: chunk culling must not change the image.
  const SurfaceMesh fine(g.pos, g.nrm, g.col, g.tri, 0.25f);
  const SurfaceMesh coarse(g.pos, g.nrm, g.col, g.tri, 100.0f);
  CHECK(fine.chunks() > coarse.chunks());
  TsdfRaycast a, b;
  fine.Rasterize(At(0.1, 0, 0), cam, 0.1f, 5.0f, &a);
  coarse.Rasterize(At(0.1, 0, 0), cam, 0.1f, 5.0f, &b);
  CHECK(cv::norm(a.depth, b.depth, cv::NORM_INF) == 0.0);
  CHECK(a.depth.at<float>(20, 20) == Approx(1.5f).margin(1e-4));  // the near square in front
  CHECK(a.depth.at<float>(2, 2) == Approx(3.0f).margin(1e-4));    // the far plane around it
  // depth_max below the far plane: only the near square is left.
  TsdfRaycast c;
  fine.Rasterize(At(0.1, 0, 0), cam, 0.1f, 2.0f, &c);
  CHECK(c.depth.at<float>(2, 2) == 0.0f);
  CHECK(c.depth.at<float>(20, 20) == Approx(1.5f).margin(1e-4));
  // depth_min beyond the near square's vertices: its triangles are skipped, the far plane shows.
  TsdfRaycast d;
  fine.Rasterize(At(0.1, 0, 0), cam, 1.6f, 5.0f, &d);
  CHECK(d.depth.at<float>(20, 20) == Approx(3.0f).margin(1e-4));
}

TEST_CASE("SurfaceMesh: a mask of pixels to draw gives the full view's values there and nothing else", "[unit]") {
  Grid g = PlaneGrid(3.0f, 5.0f, 24, true, false);
  const Grid near = PlaneGrid(1.5f, 0.3f, 6, true, false);
  const int64_t base = static_cast<int64_t>(g.pos.size());
  g.pos.insert(g.pos.end(), near.pos.begin(), near.pos.end());
  g.nrm.insert(g.nrm.end(), near.nrm.begin(), near.nrm.end());
  g.col.insert(g.col.end(), near.col.begin(), near.col.end());
  for (int64_t i : near.tri) g.tri.push_back(base + i);
  const SurfaceMesh mesh(g.pos, g.nrm, g.col, g.tri, 0.25f);
  const auto cam = Cam(40, 40, 40);
  const scene::Pose pose = At(0.1, 0.05, 0);
  TsdfRaycast full;
  mesh.Rasterize(pose, cam, 0.1f, 5.0f, &full);
  REQUIRE(cv::countNonZero(full.depth) == 40 * 40);
  // Scattered pixels, a block in a corner and the near square's edge (both surfaces meet there).
  cv::Mat only = cv::Mat::zeros(40, 40, CV_8UC1);
  for (int i = 0; i < 40 * 40; i += 13) only.at<uint8_t>(i / 40, i % 40) = 1;
  only(cv::Rect(33, 0, 7, 5)).setTo(200);
  only.row(20).setTo(7);
  TsdfRaycast part;
  mesh.Rasterize(pose, cam, 0.1f, 5.0f, &part, &only);
  const cv::Mat drawn = part.depth > 0.0f;
  CHECK(cv::countNonZero(drawn) == cv::countNonZero(only));
  CHECK(cv::countNonZero(drawn & (only == 0)) == 0);
  cv::Mat masked_depth, masked_normals, masked_colour;
  full.depth.copyTo(masked_depth, only);
  full.normals.copyTo(masked_normals, only);
  full.colour.copyTo(masked_colour, only);
  CHECK(cv::norm(part.depth, masked_depth, cv::NORM_INF) == 0.0);
  CHECK(cv::norm(part.normals, masked_normals, cv::NORM_INF) == 0.0);
  CHECK(cv::norm(part.colour, masked_colour, cv::NORM_INF) == 0.0);
  // Both surfaces appear among the drawn pixels (row 20 crosses the near square).
  CHECK(part.depth.at<float>(20, 20) == Approx(1.5f).margin(1e-4));
  CHECK(part.depth.at<float>(2, 36) == Approx(3.0f).margin(1e-4));
  // A submatrix (not continuous) works the same; an empty mask draws nothing.
  cv::Mat big = cv::Mat::zeros(50, 60, CV_8UC1);
  only.copyTo(big(cv::Rect(10, 5, 40, 40)));
  const cv::Mat roi = big(cv::Rect(10, 5, 40, 40));
  TsdfRaycast again;
  mesh.Rasterize(pose, cam, 0.1f, 5.0f, &again, &roi);
  CHECK(cv::norm(again.depth, part.depth, cv::NORM_INF) == 0.0);
  const cv::Mat none = cv::Mat::zeros(40, 40, CV_8UC1);
  mesh.Rasterize(pose, cam, 0.1f, 5.0f, &again, &none);
  CHECK(cv::countNonZero(again.depth) == 0);
  // A mask of another size or type is refused, naming what it needs.
  const cv::Mat small = cv::Mat::ones(20, 40, CV_8UC1);
  CHECK_THROWS_WITH(mesh.Rasterize(pose, cam, 0.1f, 5.0f, &again, &small), Catch::Contains("40x40"));
  const cv::Mat floats = cv::Mat::ones(40, 40, CV_32FC1);
  CHECK_THROWS_WITH(mesh.Rasterize(pose, cam, 0.1f, 5.0f, &again, &floats), Catch::Contains("CV_8UC1"));
}

/// Appends an n x n grid of quads spanning o + [0, 1] e1 + [0, 1] e2, normals along e1 x e2, colour
/// varying over it.
void AddGrid(Grid* g, const Eigen::Vector3f& o, const Eigen::Vector3f& e1, const Eigen::Vector3f& e2, int n) {
  const int64_t base = static_cast<int64_t>(g->pos.size());
  const Eigen::Vector3f normal = e1.cross(e2).normalized();
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const float s = static_cast<float>(i) / n, t = static_cast<float>(j) / n;
      g->pos.push_back(o + s * e1 + t * e2);
      g->nrm.push_back(normal);
      g->col.emplace_back(s, t, 0.5f * (s + t));
    }
  auto idx = [&](int i, int j) { return base + j * (n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      for (int64_t k : {idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)})
        g->tri.push_back(k);
}

/// Appends a latitude-longitude ball with outward normals.
void AddBall(Grid* g, const Eigen::Vector3f& centre, float radius, int rings, int segments) {
  const int64_t base = static_cast<int64_t>(g->pos.size());
  for (int r = 0; r <= rings; ++r)
    for (int k = 0; k <= segments; ++k) {
      const float th = static_cast<float>(M_PI) * r / rings, ph = 2.0f * static_cast<float>(M_PI) * k / segments;
      const Eigen::Vector3f n(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
      g->pos.push_back(centre + radius * n);
      g->nrm.push_back(n);
      g->col.emplace_back(0.2f, 0.5f + 0.4f * n.y(), 0.9f);
    }
  auto idx = [&](int r, int k) { return base + r * (segments + 1) + k; };
  for (int r = 0; r < rings; ++r)
    for (int k = 0; k < segments; ++k)
      for (int64_t i : {idx(r, k), idx(r + 1, k), idx(r + 1, k + 1), idx(r, k), idx(r + 1, k + 1), idx(r, k + 1)})
        g->tri.push_back(i);
}

/// Turns every triangle whose vertex order disagrees with its vertex normals (marching cubes winds
/// all one way; so does this scene after it), and drops the degenerate ones at the ball's poles.
void WindByNormals(Grid* g) {
  std::vector<int64_t> kept;
  for (size_t t = 0; t + 2 < g->tri.size(); t += 3) {
    int64_t a = g->tri[t], b = g->tri[t + 1], c = g->tri[t + 2];
    const Eigen::Vector3f cross = (g->pos[b] - g->pos[a]).cross(g->pos[c] - g->pos[a]);
    if (cross.norm() < 1e-9f) continue;
    if (cross.dot(g->nrm[a] + g->nrm[b] + g->nrm[c]) < 0.0f) std::swap(b, c);
    kept.insert(kept.end(), {a, b, c});
  }
  g->tri = kept;
}

/// The reference the rasteriser must match: every pixel's ray intersected with every triangle
/// (Moller-Trumbore in the camera frame), the nearest front face with all vertices at depth >=
/// depth_min and a hit at depth <= depth_max; its depth and interpolated colour.
TsdfRaycast RayCastEveryTriangle(const Grid& g, const scene::Pose& pose, const scene::CameraInfo& cam,
                                 float depth_min, float depth_max) {
  const Eigen::Matrix4d cw = pose.Inverse().ToMatrix();
  const Eigen::Matrix3f r = cw.block<3, 3>(0, 0).cast<float>();
  const Eigen::Vector3f tr = cw.block<3, 1>(0, 3).cast<float>();
  std::vector<Eigen::Vector3f> p;
  for (const Eigen::Vector3f& x : g.pos) p.push_back(r * x + tr);
  TsdfRaycast out{cv::Mat::zeros(cam.image_height, cam.image_width, CV_32FC1), cv::Mat(),
                  cv::Mat::zeros(cam.image_height, cam.image_width, CV_32FC3)};
  for (int v = 0; v < cam.image_height; ++v)
    for (int u = 0; u < cam.image_width; ++u) {
      const Eigen::Vector3f d(static_cast<float>((u - cam.cx()) / cam.fx()),
                              static_cast<float>((v - cam.cy()) / cam.fy()), 1.0f);
      float best = std::numeric_limits<float>::infinity();
      for (size_t t = 0; t + 2 < g.tri.size(); t += 3) {
        const int64_t ia = g.tri[t], ib = g.tri[t + 1], ic = g.tri[t + 2];
        const Eigen::Vector3f &a = p[ia], &b = p[ib], &c = p[ic];
        if (a.z() < depth_min || b.z() < depth_min || c.z() < depth_min) continue;
        const Eigen::Vector3f e1 = b - a, e2 = c - a;
        if (e1.cross(e2).dot(d) >= 0.0f) continue;  // seen from behind
        const Eigen::Vector3f q = d.cross(e2);
        const float inv = 1.0f / e1.dot(q);
        const Eigen::Vector3f s = -a;
        const float bu = s.dot(q) * inv;
        const Eigen::Vector3f w = s.cross(e1);
        const float bv = d.dot(w) * inv;
        if (bu < 0.0f || bv < 0.0f || bu + bv > 1.0f) continue;
        const float z = e2.dot(w) * inv;
        if (!(z > 0.0f) || z > depth_max || z >= best) continue;
        best = z;
        out.depth.at<float>(v, u) = z;
        const Eigen::Vector3f col = (1.0f - bu - bv) * g.col[ia] + bu * g.col[ib] + bv * g.col[ic];
        out.colour.at<cv::Vec3f>(v, u) = cv::Vec3f(col.x(), col.y(), col.z());
      }
    }
  return out;
}

TEST_CASE("SurfaceMesh: chunks and clusters lose no pixel: the z-buffer equals a ray cast of every triangle",
          "[unit]") {
  // A room (inward-facing walls) of 4 x 3 x 4 m with a ball in it: thousands of triangles over many
  // chunks and clusters; views from inside look at parts of it, with walls behind and beside them.
  Grid g;
  const int n = 24;
  AddGrid(&g, {-2, -1.5f, -2}, {4, 0, 0}, {0, 3, 0}, n);   // z = -2, normal +z
  AddGrid(&g, {-2, -1.5f, 2}, {0, 3, 0}, {4, 0, 0}, n);    // z = +2, normal -z
  AddGrid(&g, {-2, -1.5f, -2}, {0, 3, 0}, {0, 0, 4}, n);   // x = -2, normal +x
  AddGrid(&g, {2, -1.5f, -2}, {0, 0, 4}, {0, 3, 0}, n);    // x = +2, normal -x
  AddGrid(&g, {-2, -1.5f, -2}, {0, 0, 4}, {4, 0, 0}, n);   // y = -1.5, normal +y
  AddGrid(&g, {-2, 1.5f, -2}, {4, 0, 0}, {0, 0, 4}, n);    // y = +1.5, normal -y
  AddBall(&g, {0.3f, 0.2f, 0.9f}, 0.45f, 16, 24);
  WindByNormals(&g);
  const SurfaceMesh mesh(g.pos, g.nrm, g.col, g.tri, 0.5f);
  REQUIRE(mesh.triangles() == static_cast<int64_t>(g.tri.size() / 3));
  REQUIRE(mesh.chunks() > 20);
  const auto cam = Cam(64, 48, 45);
  const std::vector<scene::Pose> poses = {
      At(0.05, 0.03, -0.6),
      scene::Pose(Eigen::Vector3d(-0.4, 0.1, -1.1), Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()))),
      scene::Pose(Eigen::Vector3d(0.6, -0.2, 0.1), Eigen::Quaterniond(Eigen::AngleAxisd(2.4, Eigen::Vector3d::UnitY()) *
                                                                     Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()))),
      scene::Pose(Eigen::Vector3d(1.2, 0.4, 1.3), Eigen::Quaterniond(Eigen::AngleAxisd(-2.3, Eigen::Vector3d::UnitY())))};
  for (size_t k = 0; k < poses.size(); ++k) {
    CAPTURE(k);
    const float depth_min = 0.3f, depth_max = k == 3 ? 2.85f : 8.0f;
    const TsdfRaycast want = RayCastEveryTriangle(g, poses[k], cam, depth_min, depth_max);
    TsdfRaycast got;
    mesh.Rasterize(poses[k], cam, depth_min, depth_max, &got);
    const int hits = cv::countNonZero(want.depth);
    CHECK(hits > 64 * 48 / 2);
    // Pixels that disagree (one hits, the other not, or another surface): at most a few whose
    // centre lies on an edge to within float rounding. A lost cluster would be dozens.
    int disagree = 0;
    double worst_colour = 0.0;
    for (int v = 0; v < 48; ++v)
      for (int u = 0; u < 64; ++u) {
        const float a = want.depth.at<float>(v, u), b = got.depth.at<float>(v, u);
        if ((a > 0.0f) != (b > 0.0f) || std::abs(a - b) > 1e-3f * std::max(a, 1.0f)) {
          ++disagree;
          continue;
        }
        if (a > 0.0f)
          worst_colour = std::max(worst_colour, cv::norm(want.colour.at<cv::Vec3f>(v, u) - got.colour.at<cv::Vec3f>(v, u),
                                                         cv::NORM_INF));
      }
    CHECK(disagree <= 3);
    CHECK(worst_colour < 1e-3);
    // Drawing scattered pixels only gives the full view's values there.
    cv::Mat only = cv::Mat::zeros(48, 64, CV_8UC1);
    for (int i = static_cast<int>(k); i < 64 * 48; i += 29) only.at<uint8_t>(i / 64, i % 64) = 1;
    TsdfRaycast part;
    mesh.Rasterize(poses[k], cam, depth_min, depth_max, &part, &only);
    cv::Mat masked;
    got.depth.copyTo(masked, only);
    CHECK(cv::norm(part.depth, masked, cv::NORM_INF) == 0.0);
  }
}

TEST_CASE("SurfaceMesh: an empty mesh draws nothing, inconsistent arrays are refused", "[unit]") {
  const SurfaceMesh empty({}, {}, {}, {});
  TsdfRaycast r;
  empty.Rasterize(At(0, 0, 0), Cam(16, 12, 15), 0.1f, 5.0f, &r);
  CHECK(cv::countNonZero(r.depth) == 0);
  const std::vector<Eigen::Vector3f> one = {Eigen::Vector3f::Zero()};
  CHECK_THROWS_WITH(SurfaceMesh(one, {}, one, {}), Catch::Contains("normals"));
  CHECK_THROWS_WITH(SurfaceMesh(one, one, one, {0, 0}), Catch::Contains("threes"));
  CHECK_THROWS_WITH(SurfaceMesh(one, one, one, {0, 0, 1}), Catch::Contains("out of range"));
}

}  // namespace
}  // namespace p2i::fusion
