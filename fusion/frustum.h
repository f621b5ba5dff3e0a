/// @file frustum.h
/// @brief Whether a bounding sphere can reach into a pinhole camera's view (conservative): the
/// one test behind the raycast's block selection (tsdf_volume.cc) and the mesh's chunk culling
/// (surface_mesh.cc).
#pragma once

#include <cmath>

namespace p2i::fusion {

/// The sphere's centre projected to pixels (u, v) and the half-extent (mu, mv) its radius can reach
/// around it, plus one pixel; false (nothing set) when the sphere reaches the camera plane.
template <typename Vec, typename T>
bool ProjectSphere(const Vec& centre, T radius, T fx, T fy, T cx, T cy, T* u, T* v, T* mu, T* mv) {
  const T z = centre.z();
  if (z <= radius) return false;
  *u = fx * centre.x() / z + cx, *v = fy * centre.y() / z + cy;
  *mu = fx * radius / (z - radius) + T(1), *mv = fy * radius / (z - radius) + T(1);
  return true;
}

/// `centre` of the sphere in the camera frame (x right, y down, z forward), its `radius`; the view
/// spans depths [z_near, z_far] and w x h pixels of focal lengths fx, fy and principal point cx, cy.
/// False only when no point of the sphere can project into the image within that depth range.
template <typename Vec, typename T>
bool SphereMayBeInView(const Vec& centre, T radius, T z_near, T z_far, T fx, T fy, T cx, T cy, int w,
                       int h) {
  const T z = centre.z();
  if (z < z_near - radius || z > z_far + radius) return false;
  T u, v, mu, mv;
  if (!ProjectSphere(centre, radius, fx, fy, cx, cy, &u, &v, &mu, &mv)) return true;  // keep it
  return !(u < -mu || u > w + mu || v < -mv || v > h + mv);
}

/// The pixel box [u0, u1] x [v0, v1] (clamped to the image) a sphere that SphereMayBeInView can
/// cover, conservatively; the whole image when the sphere reaches the camera plane.
template <typename Vec, typename T>
void SphereScreenBox(const Vec& centre, T radius, T fx, T fy, T cx, T cy, int w, int h, int* u0,
                     int* u1, int* v0, int* v1) {
  *u0 = 0, *u1 = w - 1, *v0 = 0, *v1 = h - 1;
  T u, v, mu, mv;
  if (!ProjectSphere(centre, radius, fx, fy, cx, cy, &u, &v, &mu, &mv)) return;
  const auto clamp = [](T x, int lo, int hi) {
    return x < T(lo) ? lo : (x > T(hi) ? hi : static_cast<int>(x));
  };
  *u0 = clamp(std::floor(u - mu), 0, w - 1), *u1 = clamp(std::ceil(u + mu), 0, w - 1);
  *v0 = clamp(std::floor(v - mv), 0, h - 1), *v1 = clamp(std::ceil(v + mv), 0, h - 1);
}

}  // namespace p2i::fusion
