/// @file sim_scene.cc
/// @brief The synthetic scene renderer: per-primitive screen-space boxes, exact ray tests, a
/// z-buffer, then one deferred shading pass.
#include "scene/sim_scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "scene/sim_builtin_scenes.h"
#include "scene/sim_sensor_model.h"
#include "scene/sim_texture.h"

namespace p2i::scene {
namespace {

using Vec3f = Eigen::Vector3f;
constexpr float kNear = 0.02f;  // metres; closer hits are treated as "inside the camera"
constexpr int kRoomFaces = 6;   // primitive ids 0..5 are the room faces, objects follow

struct Primitive {
  SimShape shape = SimShape::kBox;
  int material = 0;
  Vec3f center = Vec3f::Zero();
  Vec3f half = Vec3f::Ones();  // box: half extents; cylinder: (r, r, h/2); sphere: (r, r, r)
  float cos_yaw = 1.0f, sin_yaw = 0.0f;
  float radius = 0.5f;
  Eigen::Vector3d corners[8];  // world-frame bounding box corners, bit i of the index = +axis i
};

struct Light {
  bool directional = false;
  Vec3f position_or_direction = Vec3f::Zero();  // directional: unit vector towards the light
  Vec3f color = Vec3f::Ones();                  // colour * intensity
  float inv_range2 = 0.04f;
};

// Rotations about z by the object's yaw, world <-> local.
inline Vec3f ToLocal(const Primitive& p, const Vec3f& v) {
  return {p.cos_yaw * v.x() + p.sin_yaw * v.y(), -p.sin_yaw * v.x() + p.cos_yaw * v.y(), v.z()};
}
inline Vec3f ToWorld(const Primitive& p, const Vec3f& v) {
  return {p.cos_yaw * v.x() - p.sin_yaw * v.y(), p.sin_yaw * v.x() + p.cos_yaw * v.y(), v.z()};
}

/// The scene compiled for the inner loops (floats, per-object corners). Immutable once built.
struct CompiledScene {
  Vec3f room_min, room_max;
  int face_material[kRoomFaces];
  std::vector<Primitive> prims;
  std::vector<SimTextureSampler> samplers;
  std::vector<Light> lights;
  std::vector<float> specular, shininess;  // per material; specular 0 = Lambertian
  float ambient = 0.3f;
};

void CompileScene(const SimSceneDescription& description, CompiledScene* c) {
  c->room_min = description.RoomMin().cast<float>();
  c->room_max = description.RoomMax().cast<float>();
  for (int i = 0; i < 4; ++i) c->face_material[i] = description.wall_materials[i];
  c->face_material[4] = description.floor_material;
  c->face_material[5] = description.ceiling_material;
  for (const auto& m : description.materials) {
    c->samplers.emplace_back(m);
    c->specular.push_back(static_cast<float>(m.specular));
    c->shininess.push_back(static_cast<float>(m.shininess));
  }
  c->ambient = static_cast<float>(description.ambient);
  for (const auto& l : description.lights) {
    Light cl;
    cl.directional = l.type == SimLight::Type::kDirectional;
    const Eigen::Vector3d towards =
        cl.directional ? Eigen::Vector3d(-l.direction.normalized()) : l.position;
    cl.position_or_direction = towards.cast<float>();
    cl.color = (l.color * l.intensity).cast<float>();
    cl.inv_range2 = static_cast<float>(1.0 / (l.range * l.range));
    c->lights.push_back(cl);
  }
  for (const auto& o : description.objects) {
    Primitive p;
    p.shape = o.shape;
    p.material = o.material;
    p.center = o.center.cast<float>();
    p.radius = static_cast<float>(o.radius);
    Eigen::Vector3d half = Eigen::Vector3d::Zero();
    switch (o.shape) {
      case SimShape::kBox:
        half = o.size / 2.0;
        p.cos_yaw = static_cast<float>(std::cos(o.yaw_deg * M_PI / 180.0));
        p.sin_yaw = static_cast<float>(std::sin(o.yaw_deg * M_PI / 180.0));
        break;
      case SimShape::kCylinder:
        half = Eigen::Vector3d(o.radius, o.radius, o.height / 2.0);
        break;
      case SimShape::kSphere:
        half = Eigen::Vector3d::Constant(o.radius);
        break;
    }
    p.half = half.cast<float>();
    const double cy = o.shape == SimShape::kBox ? std::cos(o.yaw_deg * M_PI / 180.0) : 1.0;
    const double sy = o.shape == SimShape::kBox ? std::sin(o.yaw_deg * M_PI / 180.0) : 0.0;
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3d l((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(),
                              (i & 4) ? half.z() : -half.z());
      p.corners[i] =
          o.center + Eigen::Vector3d(cy * l.x() - sy * l.y(), sy * l.x() + cy * l.y(), l.z());
    }
    c->prims.push_back(p);
  }
}

/// The rays of one frame. The ray of pixel (u, v) is d0 + u * du + v * dv: its camera-frame z
/// is 1, so the ray parameter of a hit is its z-depth.
struct FrameRays {
  int w = 0, h = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  Eigen::Matrix3d world_to_cam;
  Eigen::Vector3d origin_d;
  Vec3f origin, d0, du, dv;
  Vec3f Row(int v) const { return d0 + static_cast<float>(v) * dv; }
};

FrameRays MakeFrameRays(const Pose& camera_to_world, const CameraInfo& camera) {
  FrameRays r;
  r.w = camera.image_width, r.h = camera.image_height;
  r.fx = camera.fx(), r.fy = camera.fy(), r.cx = camera.cx(), r.cy = camera.cy();
  if (r.w <= 0 || r.h <= 0 || !(r.fx > 0.0) || !(r.fy > 0.0) || !std::isfinite(r.cx) ||
      !std::isfinite(r.cy)) {
    throw std::invalid_argument("SimScene::Render: camera '" + camera.camera_name +
                                "' needs a positive image size and focal lengths (got " +
                                std::to_string(r.w) + "x" + std::to_string(r.h) + ", fx " +
                                std::to_string(r.fx) + ", fy " + std::to_string(r.fy) + ")");
  }
  const Eigen::Matrix3d rot_d = camera_to_world.rotation().toRotationMatrix();
  r.world_to_cam = rot_d.transpose();
  r.origin_d = camera_to_world.translation();
  const Eigen::Matrix3f rot = rot_d.cast<float>();
  r.origin = r.origin_d.cast<float>();
  r.d0 = rot * Vec3f(static_cast<float>(-r.cx / r.fx), static_cast<float>(-r.cy / r.fy), 1.0f);
  r.du = rot.col(0) / static_cast<float>(r.fx);
  r.dv = rot.col(1) / static_cast<float>(r.fy);
  return r;
}

/// Nearest hit per pixel: z-depth (inf = none) and primitive id (-1 = none).
struct ZBuffer {
  std::vector<float> z;
  std::vector<std::int16_t> ids;
  explicit ZBuffer(std::size_t n) : z(n, std::numeric_limits<float>::infinity()), ids(n, -1) {}
};

/// The room: the exit point of each ray from the room's box (faces 0..5 = -x, +x, -y, +y, -z, +z).
void RasterRoom(const CompiledScene& sc, const FrameRays& r, ZBuffer* zb) {
  for (int v = 0; v < r.h; ++v) {
    const Vec3f row = r.Row(v);
    for (int u = 0; u < r.w; ++u) {
      const Vec3f d = row + static_cast<float>(u) * r.du;
      float t_best = std::numeric_limits<float>::infinity();
      int face = -1;
      for (int a = 0; a < 3; ++a) {
        if (d[a] > 1e-12f) {
          const float t = (sc.room_max[a] - r.origin[a]) / d[a];
          if (t < t_best) t_best = t, face = 2 * a + 1;
        } else if (d[a] < -1e-12f) {
          const float t = (sc.room_min[a] - r.origin[a]) / d[a];
          if (t < t_best) t_best = t, face = 2 * a;
        }
      }
      if (face >= 0 && t_best > kNear) {
        const std::size_t i = static_cast<std::size_t>(v) * r.w + u;
        zb->z[i] = t_best;
        zb->ids[i] = static_cast<std::int16_t>(face);
      }
    }
  }
}

struct PixelRect {
  int u0 = 0, u1 = -1, v0 = 0, v1 = -1;
  bool Empty() const { return u0 > u1 || v0 > v1; }
};

/// The pixels covered by a primitive's bounding box clipped at the near plane (one pixel of
/// margin), or an empty rectangle when it is entirely behind the camera or off screen.
PixelRect ProjectedBounds(const Primitive& p, const FrameRays& r) {
  static constexpr int kEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                        {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  Eigen::Vector3d pc[8];
  for (int i = 0; i < 8; ++i) pc[i] = r.world_to_cam * (p.corners[i] - r.origin_d);
  double umin = 1e30, umax = -1e30, vmin = 1e30, vmax = -1e30;
  bool any = false;
  const auto add = [&](const Eigen::Vector3d& q) {
    const double uu = r.fx * q.x() / q.z() + r.cx, vv = r.fy * q.y() / q.z() + r.cy;
    umin = std::min(umin, uu), umax = std::max(umax, uu);
    vmin = std::min(vmin, vv), vmax = std::max(vmax, vv);
    any = true;
  };
  const double near = kNear;
  for (int i = 0; i < 8; ++i) {
    if (pc[i].z() >= near) add(pc[i]);
  }
  for (const auto& e : kEdges) {
    const Eigen::Vector3d& a = pc[e[0]];
    const Eigen::Vector3d& b = pc[e[1]];
    if ((a.z() < near) != (b.z() < near)) {
      const double s = (near - a.z()) / (b.z() - a.z());
      add(a + s * (b - a));
    }
  }
  PixelRect rect;
  if (!any) return rect;
  rect.u0 = std::max(0, static_cast<int>(std::floor(umin)) - 1);
  rect.u1 = std::min(r.w - 1, static_cast<int>(std::ceil(umax)) + 1);
  rect.v0 = std::max(0, static_cast<int>(std::floor(vmin)) - 1);
  rect.v1 = std::min(r.h - 1, static_cast<int>(std::ceil(vmax)) + 1);
  return rect;
}

// Ray tests in the primitive's local frame: origin o, direction d (camera z = 1 per unit t).
// Each returns the first hit's t beyond kNear from outside, or -1. A ray starting inside the
// solid hits nothing (its faces are culled).

inline float IntersectBox(const Primitive& p, const Vec3f& o, const Vec3f& d) {
  float tmin = -std::numeric_limits<float>::infinity();
  float tmax = std::numeric_limits<float>::infinity();
  for (int a = 0; a < 3; ++a) {
    const float inv = 1.0f / d[a];  // +-inf for d[a] == 0 works with the slab test
    float t1 = (-p.half[a] - o[a]) * inv, t2 = (p.half[a] - o[a]) * inv;
    if (t1 > t2) std::swap(t1, t2);
    tmin = std::max(tmin, t1);
    tmax = std::min(tmax, t2);
  }
  return tmin <= tmax && tmin > kNear ? tmin : -1.0f;  // from inside: culled (back faces)
}

inline float IntersectCylinder(const Primitive& p, const Vec3f& o, const Vec3f& d) {
  const float a = d.x() * d.x() + d.y() * d.y();
  const float b = o.x() * d.x() + o.y() * d.y();
  const float c = o.x() * o.x() + o.y() * o.y() - p.radius * p.radius;
  float best = std::numeric_limits<float>::infinity();
  if (a > 1e-12f) {
    const float disc = b * b - a * c;
    if (disc >= 0.0f) {
      const float ts = (-b - std::sqrt(disc)) / a;
      const float z = o.z() + ts * d.z();
      if (ts > kNear && std::abs(z) <= p.half.z()) best = ts;
    }
  }
  if (std::abs(d.z()) > 1e-12f) {
    // Only the cap facing the camera can be the first hit from outside.
    const float cap = o.z() > 0.0f ? p.half.z() : -p.half.z();
    if (std::abs(o.z()) > p.half.z()) {
      const float tc = (cap - o.z()) / d.z();
      const float x = o.x() + tc * d.x(), y = o.y() + tc * d.y();
      if (tc > kNear && x * x + y * y <= p.radius * p.radius) best = std::min(best, tc);
    }
  }
  // From inside the circle the side root is behind the camera, so `best` is a cap or nothing;
  // from inside the solid nothing is hit (culled).
  return best < std::numeric_limits<float>::infinity() ? best : -1.0f;
}

inline float IntersectSphere(const Primitive& p, const Vec3f& o, const Vec3f& d) {
  const float a = d.squaredNorm();
  const float b = o.dot(d);
  const float c = o.squaredNorm() - p.radius * p.radius;
  const float disc = b * b - a * c;
  if (c > 0.0f && disc >= 0.0f) {
    const float ts = (-b - std::sqrt(disc)) / a;
    if (ts > kNear) return ts;
  }
  return -1.0f;
}

/// Exact ray tests of one primitive over `rect`, keeping the nearer hit per pixel.
template <typename Intersect>
void RasterPixels(const Primitive& p, std::int16_t id, const FrameRays& r, const PixelRect& rect,
                  Intersect intersect, ZBuffer* zb) {
  const Vec3f o = ToLocal(p, r.origin - p.center);
  const Vec3f ld0 = ToLocal(p, r.d0), ldu = ToLocal(p, r.du), ldv = ToLocal(p, r.dv);
  for (int v = rect.v0; v <= rect.v1; ++v) {
    const Vec3f row = ld0 + static_cast<float>(v) * ldv;
    float* zrow = &zb->z[static_cast<std::size_t>(v) * r.w];
    std::int16_t* irow = &zb->ids[static_cast<std::size_t>(v) * r.w];
    for (int u = rect.u0; u <= rect.u1; ++u) {
      const float t = intersect(p, o, row + static_cast<float>(u) * ldu);
      if (t > 0.0f && t < zrow[u]) {
        zrow[u] = t;
        irow[u] = id;
      }
    }
  }
}

/// Objects: exact ray tests inside each one's clipped, projected bounding box.
void RasterObjects(const CompiledScene& sc, const FrameRays& r, ZBuffer* zb) {
  for (std::size_t pi = 0; pi < sc.prims.size(); ++pi) {
    const Primitive& p = sc.prims[pi];
    const PixelRect rect = ProjectedBounds(p, r);
    if (rect.Empty()) continue;
    const auto id = static_cast<std::int16_t>(kRoomFaces + pi);
    switch (p.shape) {
      case SimShape::kBox:
        RasterPixels(p, id, r, rect, IntersectBox, zb);
        break;
      case SimShape::kCylinder:
        RasterPixels(p, id, r, rect, IntersectCylinder, zb);
        break;
      case SimShape::kSphere:
        RasterPixels(p, id, r, rect, IntersectSphere, zb);
        break;
    }
  }
}

/// What shading needs to know about a visible point: its world normal (towards the outside of
/// objects, into the room for its faces), texture coordinates in metres and material.
struct SurfacePoint {
  Vec3f normal = Vec3f::UnitZ();
  float su = 0.0f, sv = 0.0f;
  int material = 0;
};

SurfacePoint RoomSurfaceAt(const CompiledScene& sc, int face, const Vec3f& hit) {
  SurfacePoint s;
  const int axis = face / 2;
  s.normal = Vec3f::Zero();
  s.normal[axis] = (face & 1) ? -1.0f : 1.0f;  // inward
  s.material = sc.face_material[face];
  if (axis == 0) {
    s.su = hit.y() - sc.room_min.y(), s.sv = hit.z();
  } else if (axis == 1) {
    s.su = hit.x() - sc.room_min.x(), s.sv = hit.z();
  } else {
    s.su = hit.x() - sc.room_min.x(), s.sv = hit.y() - sc.room_min.y();
  }
  return s;
}

SurfacePoint ObjectSurfaceAt(const Primitive& p, const Vec3f& hit) {
  SurfacePoint s;
  s.material = p.material;
  const Vec3f l = ToLocal(p, hit - p.center);
  switch (p.shape) {
    case SimShape::kBox: {
      const Vec3f r = l.cwiseAbs().cwiseQuotient(p.half);
      int a = 0;
      if (r.y() > r[a]) a = 1;
      if (r.z() > r[a]) a = 2;
      Vec3f ln = Vec3f::Zero();
      ln[a] = l[a] > 0.0f ? 1.0f : -1.0f;
      s.normal = ToWorld(p, ln);
      const int b = a == 0 ? 1 : 0, c = a == 2 ? 1 : 2;
      s.su = l[b] + p.half[b], s.sv = l[c] + p.half[c];
      break;
    }
    case SimShape::kCylinder:
      if (std::abs(std::abs(l.z()) - p.half.z()) < 1e-3f &&
          l.x() * l.x() + l.y() * l.y() < p.radius * p.radius * 0.998f) {
        s.normal = Vec3f(0.0f, 0.0f, l.z() > 0.0f ? 1.0f : -1.0f);
        s.su = l.x(), s.sv = l.y();
      } else {
        s.normal = Vec3f(l.x(), l.y(), 0.0f) / p.radius;
        s.su = std::atan2(l.y(), l.x()) * p.radius, s.sv = l.z() + p.half.z();
      }
      break;
    case SimShape::kSphere:
      s.normal = l / p.radius;
      s.su = std::atan2(s.normal.y(), s.normal.x()) * p.radius;
      s.sv = std::asin(std::clamp(s.normal.z(), -1.0f, 1.0f)) * p.radius;
      break;
  }
  return s;
}

/// Ambient plus Lambertian light arriving at `hit` with `normal` (no shadows).
Vec3f Irradiance(const CompiledScene& sc, const Vec3f& normal, const Vec3f& hit) {
  Vec3f light = Vec3f::Constant(sc.ambient);
  for (const Light& lt : sc.lights) {
    if (lt.directional) {
      const float ndl = normal.dot(lt.position_or_direction);
      if (ndl > 0.0f) light += ndl * lt.color;
    } else {
      const Vec3f to = lt.position_or_direction - hit;
      const float dist2 = to.squaredNorm();
      const float ndl = normal.dot(to) / std::sqrt(dist2);
      if (ndl > 0.0f) light += (ndl / (1.0f + dist2 * lt.inv_range2)) * lt.color;
    }
  }
  return light;
}

/// Blinn-Phong highlight of the lights at `hit` seen along `d` (light colour, unnormalised).
Vec3f Highlight(const CompiledScene& sc, const Vec3f& normal, const Vec3f& hit, const Vec3f& d,
                float shininess) {
  const Vec3f to_eye = -d.normalized();
  Vec3f sum = Vec3f::Zero();
  for (const Light& lt : sc.lights) {
    Vec3f to_light = lt.position_or_direction;
    float attenuation = 1.0f;
    if (!lt.directional) {
      to_light -= hit;
      const float dist2 = to_light.squaredNorm();
      to_light /= std::sqrt(dist2);
      attenuation = 1.0f / (1.0f + dist2 * lt.inv_range2);
    }
    if (normal.dot(to_light) <= 0.0f) continue;
    const float ndh = normal.dot((to_light + to_eye).normalized());
    if (ndh > 0.0f) sum += (attenuation * std::pow(ndh, shininess)) * lt.color;
  }
  return sum;
}

/// One frame before the sensor's colour pipeline: linear RGB scaled to 8-bit units (255 = white
/// albedo fully lit; not clamped), z-depth and, when asked for, |cos| of each hit's incidence.
struct LinearFrame {
  int w = 0, h = 0;
  std::vector<float> rgb;  // 3 per pixel, row-major
  cv::Mat depth;           // CV_32FC1, 0 = nothing hit
  std::vector<float> incidence_cos;
};

/// Deferred shading: every visible pixel is shaded exactly once; empty pixels are black with
/// depth 0.
void Shade(const CompiledScene& sc, const FrameRays& r, const ZBuffer& zb, LinearFrame* f) {
  f->w = r.w, f->h = r.h;
  f->rgb.assign(static_cast<std::size_t>(r.w) * r.h * 3, 0.0f);
  f->depth.create(r.h, r.w, CV_32FC1);
  for (int v = 0; v < r.h; ++v) {
    float* depth_row = f->depth.ptr<float>(v);
    const Vec3f row = r.Row(v);
    for (int u = 0; u < r.w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * r.w + u;
      const int id = zb.ids[i];
      if (id < 0) {
        depth_row[u] = 0.0f;
        continue;
      }
      const float t = zb.z[i];
      const Vec3f d = row + static_cast<float>(u) * r.du;
      const Vec3f hit = r.origin + t * d;
      const SurfacePoint s = id < kRoomFaces ? RoomSurfaceAt(sc, id, hit)
                                             : ObjectSurfaceAt(sc.prims[id - kRoomFaces], hit);
      float albedo[3];
      sc.samplers[s.material].Sample(s.su, s.sv, albedo);
      const Vec3f light = Irradiance(sc, s.normal, hit);
      float* px = &f->rgb[3 * i];
      for (int k = 0; k < 3; ++k) px[k] = albedo[k] * light[k] * 255.0f;
      if (sc.specular[s.material] > 0.0f) {
        const Vec3f spec = Highlight(sc, s.normal, hit, d, sc.shininess[s.material]);
        for (int k = 0; k < 3; ++k) px[k] += sc.specular[s.material] * spec[k] * 255.0f;
      }
      depth_row[u] = t;
      if (!f->incidence_cos.empty()) f->incidence_cos[i] = std::abs(s.normal.dot(d)) / d.norm();
    }
  }
}

LinearFrame RenderCentres(const CompiledScene& sc, const Pose& pose, const CameraInfo& camera,
                          bool with_incidence) {
  const FrameRays rays = MakeFrameRays(pose, camera);
  ZBuffer zbuf(static_cast<std::size_t>(rays.w) * rays.h);
  RasterRoom(sc, rays, &zbuf);
  RasterObjects(sc, rays, &zbuf);
  LinearFrame f;
  if (with_incidence) f.incidence_cos.assign(zbuf.z.size(), 1.0f);
  Shade(sc, rays, zbuf, &f);
  return f;
}

/// The camera whose n x n pixels tile each pixel of `camera`: pixel (n u + j, n v + k) looks
/// through (u + (j + 0.5) / n - 0.5, v + (k + 0.5) / n - 0.5) of `camera` (pixel centres at
/// integer coordinates), so for odd n the middle one is the centre ray.
CameraInfo SubPixelCamera(const CameraInfo& camera, int n) {
  return CameraInfo::Pinhole(camera.image_width * n, camera.image_height * n, camera.fx() * n,
                             camera.fy() * n, n * (camera.cx() + 0.5) - 0.5,
                             n * (camera.cy() + 0.5) - 0.5);
}

/// The linear frame at `camera`: colour the mean of n x n rays over each pixel's area (n odd),
/// depth and incidence those of the centre ray.
LinearFrame RenderLinear(const CompiledScene& sc, const Pose& pose, const CameraInfo& camera,
                         bool with_incidence, int n) {
  if (n <= 1) return RenderCentres(sc, pose, camera, with_incidence);
  const LinearFrame fine = RenderCentres(sc, pose, SubPixelCamera(camera, n), with_incidence);
  LinearFrame f;
  f.w = camera.image_width, f.h = camera.image_height;
  f.rgb.assign(static_cast<std::size_t>(f.w) * f.h * 3, 0.0f);
  f.depth.create(f.h, f.w, CV_32FC1);
  if (with_incidence) f.incidence_cos.resize(static_cast<std::size_t>(f.w) * f.h);
  const float inv = 1.0f / static_cast<float>(n * n);
  const int mid = n / 2;
  for (int v = 0; v < f.h; ++v) {
    float* depth_row = f.depth.ptr<float>(v);
    for (int u = 0; u < f.w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * f.w + u;
      float* out = &f.rgb[3 * i];
      for (int k = 0; k < n; ++k) {
        const float* in = &fine.rgb[3 * ((static_cast<std::size_t>(v) * n + k) * fine.w +
                                         static_cast<std::size_t>(u) * n)];
        for (int j = 0; j < 3 * n; ++j) out[j % 3] += in[j];
      }
      for (int c = 0; c < 3; ++c) out[c] *= inv;
      const int cv = v * n + mid, cu = u * n + mid;
      depth_row[u] = fine.depth.at<float>(cv, cu);
      if (with_incidence)
        f.incidence_cos[i] = fine.incidence_cos[static_cast<std::size_t>(cv) * fine.w + cu];
    }
  }
  return f;
}

// Depth of a moving camera: a pixel whose surface changes during the shutter time by more than
// this (relative) mixes two surfaces, which a depth sensor reports as a hole.
constexpr float kMixedDepth = 0.05f;

/// Motion blur: RGB becomes the mean of `samples` renders at poses evenly spread from shutter
/// open to close; depth keeps the frame's own pose, with holes where the surface changed.
void BlurOverShutter(const CompiledScene& sc, const CameraInfo& camera, const Pose& open,
                     const Pose& close, int samples, int pixel_samples, LinearFrame* f) {
  std::vector<float> sum(f->rgb.size(), 0.0f);
  cv::Mat mixed = cv::Mat::zeros(f->h, f->w, CV_8UC1);
  for (int s = 0; s < samples; ++s) {
    const Pose p = Pose::Interpolate(open, close, (s + 0.5) / samples);
    const LinearFrame sub = RenderLinear(sc, p, camera, false, pixel_samples);
    for (std::size_t k = 0; k < sum.size(); ++k) sum[k] += sub.rgb[k];
    for (int v = 0; v < f->h; ++v) {
      const float* z = f->depth.ptr<float>(v);
      const float* zs = sub.depth.ptr<float>(v);
      std::uint8_t* m = mixed.ptr<std::uint8_t>(v);
      for (int u = 0; u < f->w; ++u) {
        if (std::abs(zs[u] - z[u]) > kMixedDepth * z[u]) m[u] = 1;
      }
    }
  }
  const float inv = 1.0f / static_cast<float>(samples);
  for (std::size_t k = 0; k < sum.size(); ++k) f->rgb[k] = sum[k] * inv;
  f->depth.setTo(0.0f, mixed);
}

}  // namespace

struct SimScene::Compiled : CompiledScene {};

SimScene::SimScene(SimSceneDescription description, SimSensorOptions sensor)
    : description_(std::move(description)), sensor_(sensor) {
  description_.Validate();
  sensor_.Validate();
  auto c = std::make_shared<Compiled>();
  CompileScene(description_, c.get());
  compiled_ = std::move(c);
}

SimScene SimScene::FromYamlFile(const std::string& path) {
  return SimScene(SimSceneDescription::FromYamlFile(path));
}

SimScene SimScene::FromYamlString(const std::string& text, const std::string& source) {
  return SimScene(SimSceneDescription::FromYamlString(text, source));
}

SimScene SimScene::BuiltIn(const std::string& name) {
  return FromYamlString(BuiltInYaml(name), "builtin:" + name);
}

std::vector<std::string> SimScene::BuiltInNames() { return BuiltInSceneNames(); }

SimScene SimScene::FromSpec(const std::string& spec) {
  const std::string prefix = "builtin:";
  if (spec.rfind(prefix, 0) == 0) return BuiltIn(spec.substr(prefix.size()));
  for (const std::string& name : BuiltInNames()) {
    if (spec == name && !std::filesystem::exists(spec)) return BuiltIn(name);
  }
  if (!std::filesystem::exists(spec)) {
    std::string names;
    for (const std::string& n : BuiltInNames()) names += " builtin:" + n;
    throw std::runtime_error("scene '" + spec + "' is not a file; built-in scenes:" + names);
  }
  return FromYamlFile(spec);
}

CameraInfo SimScene::DefaultCamera(int width, int height) {
  const double f = 525.0 * width / 640.0;
  return CameraInfo::Pinhole(width, height, f, f, (width - 1) / 2.0, (height - 1) / 2.0, "sim");
}

const std::string& SimScene::BuiltInYaml(const std::string& name) { return BuiltInSceneYaml(name); }

void SimScene::set_sensor_options(const SimSensorOptions& sensor) {
  sensor.Validate();
  sensor_ = sensor;
}

SimBounds SimScene::Bounds() const { return {description_.RoomMin(), description_.RoomMax()}; }

bool SimScene::IsFree(const Eigen::Vector3d& point, double clearance) const {
  if (!Bounds().Contains(point, clearance)) return false;
  const Vec3f q = point.cast<float>();
  const auto cl = static_cast<float>(clearance);
  for (const auto& p : compiled_->prims) {
    const Vec3f l = ToLocal(p, q - p.center);
    switch (p.shape) {
      case SimShape::kBox:
        if ((l.cwiseAbs() - p.half).maxCoeff() <= cl) return false;
        break;
      case SimShape::kCylinder:
        if (std::hypot(l.x(), l.y()) <= p.radius + cl && std::abs(l.z()) <= p.half.z() + cl) {
          return false;
        }
        break;
      case SimShape::kSphere:
        if (l.norm() <= p.radius + cl) return false;
        break;
    }
  }
  return true;
}

RgbdSample SimScene::Render(const Pose& camera_to_world, const CameraInfo& camera) const {
  return RenderImpl(camera_to_world, camera, 0.0, false, nullptr);
}

RgbdSample SimScene::Render(const Pose& camera_to_world, const CameraInfo& camera,
                            double stamp) const {
  return RenderImpl(camera_to_world, camera, stamp, true, nullptr);
}

RgbdSample SimScene::Render(const Pose& camera_to_world, const CameraInfo& camera, double stamp,
                            const SimExposure& exposure) const {
  return RenderImpl(camera_to_world, camera, stamp, true, &exposure);
}

RgbdSample SimScene::RenderOnTrajectory(const std::vector<StampedPose>& trajectory,
                                        std::size_t index, const CameraInfo& camera) const {
  if (index >= trajectory.size()) {
    throw std::out_of_range("SimScene::RenderOnTrajectory: frame " + std::to_string(index) +
                            " of a trajectory of " + std::to_string(trajectory.size()));
  }
  const StampedPose& p = trajectory[index];
  if (!sensor_.MotionBlur()) return Render(p.pose, camera, p.stamp);
  return Render(p.pose, camera, p.stamp,
                ExposureOnTrajectory(trajectory, index, sensor_.exposure_time_s));
}

SimExposure ExposureOnTrajectory(const std::vector<StampedPose>& trajectory, std::size_t index,
                                 double exposure_time_s) {
  const StampedPose& p = trajectory.at(index);
  const auto at = [&](double t) {
    if (t <= trajectory.front().stamp) return trajectory.front().pose;
    if (t >= trajectory.back().stamp) return trajectory.back().pose;
    return InterpolateAt(trajectory, t).value_or(p.pose);
  };
  return {at(p.stamp - exposure_time_s / 2.0), at(p.stamp + exposure_time_s / 2.0)};
}

RgbdSample SimScene::RenderImpl(const Pose& camera_to_world, const CameraInfo& camera, double stamp,
                                bool stamped, const SimExposure* exposure) const {
  const Compiled& sc = *compiled_;
  const bool noise = sensor_.AnyNoise();
  LinearFrame f = RenderLinear(sc, camera_to_world, camera, noise, sensor_.pixel_samples);
  if (exposure != nullptr && sensor_.MotionBlur() &&
      !exposure->open.equals(exposure->close, 0.0)) {
    BlurOverShutter(sc, camera, exposure->open, exposure->close, sensor_.motion_blur_samples,
                    sensor_.pixel_samples, &f);
  }
  RgbdSample out;
  out.pose = camera_to_world;
  out.stamp = stamp;
  out.depth = f.depth;
  QuantizeRgb(f.rgb, f.w, f.h, SensorColourGains(sensor_, f.rgb, stamp), &out.rgb);
  if (noise) {
    const std::uint64_t key = SensorNoiseKey(sensor_.seed, camera_to_world, f.w, f.h, stamp, stamped);
    ApplySensorNoise(sensor_, key, f.incidence_cos, &out);
  }
  return out;
}

}  // namespace p2i::scene
