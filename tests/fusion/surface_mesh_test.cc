/// @file surface_mesh_test.cc
/// @brief SurfaceMesh: the z-buffer gives exact depth, normals and colour of known triangles,
/// front faces only, no crack along shared edges, chunk culling loses nothing, and a mask of
/// pixels to draw gives exactly those pixels.
#include <cmath>
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
