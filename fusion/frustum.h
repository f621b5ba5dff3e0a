/// @file frustum.h
/// @brief Whether a bounding sphere can reach into a pinhole camera's view (conservative): the
/// one test behind the raycast's block selection (tsdf_volume.cc) and the mesh's chunk culling
/// (surface_mesh.cc).
#pragma once

namespace p2i::fusion {

/// `centre` of the sphere in the camera frame (x right, y down, z forward), its `radius`; the view
/// spans depths [z_near, z_far] and w x h pixels of focal lengths fx, fy and principal point cx, cy.
/// False only when no point of the sphere can project into the image within that depth range.
template <typename Vec, typename T>
bool SphereMayBeInView(const Vec& centre, T radius, T z_near, T z_far, T fx, T fy, T cx, T cy, int w,
                       int h) {
  const T z = centre.z();
  if (z < z_near - radius || z > z_far + radius) return false;
  if (z <= radius) return true;  // the sphere reaches the camera plane: keep it
  const T u = fx * centre.x() / z + cx, v = fy * centre.y() / z + cy;
  const T mu = fx * radius / (z - radius) + T(1), mv = fy * radius / (z - radius) + T(1);
  return !(u < -mu || u > w + mu || v < -mv || v > h + mv);
}

}  // namespace p2i::fusion
