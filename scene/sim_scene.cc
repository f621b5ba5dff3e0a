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

std::uint64_t Mix64(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  x ^= x >> 31;
  return x;
}

/// A uniform number in [0, 1) from 16 bits.
inline float Uniform16(std::uint64_t bits) {
  return static_cast<float>(bits & 0xffffu) * (1.0f / 65536.0f);
}

/// An approximately standard-normal number from 64 random bits: the sum of four 16-bit
/// uniforms (Irwin-Hall), centred and scaled to unit variance. Tails end at +-3.46 sigma, which
/// is fine for sensor noise and much cheaper than std::normal_distribution.
inline float Gaussian4(std::uint64_t bits) {
  const float sum =
      Uniform16(bits) + Uniform16(bits >> 16) + Uniform16(bits >> 32) + Uniform16(bits >> 48);
  return (sum - 2.0f) * 1.7320508f;
}

}  // namespace

struct SimScene::Compiled {
  Vec3f room_min, room_max;
  int face_material[kRoomFaces];
  std::vector<Primitive> prims;
  std::vector<SimTextureSampler> samplers;
  std::vector<Light> lights;
  float ambient = 0.3f;
};

SimScene::SimScene(SimSceneDescription description, SimSensorOptions sensor)
    : description_(std::move(description)), sensor_(sensor) {
  description_.Validate();
  sensor_.Validate();
  auto c = std::make_shared<Compiled>();
  c->room_min = description_.RoomMin().cast<float>();
  c->room_max = description_.RoomMax().cast<float>();
  for (int i = 0; i < 4; ++i) c->face_material[i] = description_.wall_materials[i];
  c->face_material[4] = description_.floor_material;
  c->face_material[5] = description_.ceiling_material;
  for (const auto& m : description_.materials) c->samplers.emplace_back(m);
  c->ambient = static_cast<float>(description_.ambient);
  for (const auto& l : description_.lights) {
    Light cl;
    cl.directional = l.type == SimLight::Type::kDirectional;
    const Eigen::Vector3d towards =
        cl.directional ? Eigen::Vector3d(-l.direction.normalized()) : l.position;
    cl.position_or_direction = towards.cast<float>();
    cl.color = (l.color * l.intensity).cast<float>();
    cl.inv_range2 = static_cast<float>(1.0 / (l.range * l.range));
    c->lights.push_back(cl);
  }
  for (const auto& o : description_.objects) {
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
  return RenderImpl(camera_to_world, camera, 0.0, false);
}

RgbdSample SimScene::Render(const Pose& camera_to_world, const CameraInfo& camera,
                            double stamp) const {
  return RenderImpl(camera_to_world, camera, stamp, true);
}

RgbdSample SimScene::RenderImpl(const Pose& camera_to_world, const CameraInfo& camera, double stamp,
                                bool stamped) const {
  const int w = camera.image_width, h = camera.image_height;
  const double fx = camera.fx(), fy = camera.fy(), cx = camera.cx(), cy = camera.cy();
  if (w <= 0 || h <= 0 || !(fx > 0.0) || !(fy > 0.0) || !std::isfinite(cx) || !std::isfinite(cy)) {
    throw std::invalid_argument("SimScene::Render: camera '" + camera.camera_name +
                                "' needs a positive image size and focal lengths (got " +
                                std::to_string(w) + "x" + std::to_string(h) + ", fx " +
                                std::to_string(fx) + ", fy " + std::to_string(fy) + ")");
  }
  const Compiled& sc = *compiled_;
  const Eigen::Matrix3d rot_d = camera_to_world.rotation().toRotationMatrix();
  const Eigen::Vector3d origin_d = camera_to_world.translation();
  const Eigen::Matrix3f rot = rot_d.cast<float>();
  const Vec3f origin = origin_d.cast<float>();
  // The ray of pixel (u, v) is d0 + u * du + v * dv: its camera-frame z is 1, so the ray
  // parameter of a hit is its z-depth.
  const Vec3f d0 = rot * Vec3f(static_cast<float>(-cx / fx), static_cast<float>(-cy / fy), 1.0f);
  const Vec3f du = rot.col(0) / static_cast<float>(fx);
  const Vec3f dv = rot.col(1) / static_cast<float>(fy);

  const std::size_t n = static_cast<std::size_t>(w) * h;
  std::vector<float> zbuf(n, std::numeric_limits<float>::infinity());
  std::vector<std::int16_t> ids(n, -1);

  // Room: the exit point of the ray from the room's box.
  for (int v = 0; v < h; ++v) {
    const Vec3f row = d0 + static_cast<float>(v) * dv;
    for (int u = 0; u < w; ++u) {
      const Vec3f d = row + static_cast<float>(u) * du;
      float t_best = std::numeric_limits<float>::infinity();
      int face = -1;
      for (int a = 0; a < 3; ++a) {
        if (d[a] > 1e-12f) {
          const float t = (sc.room_max[a] - origin[a]) / d[a];
          if (t < t_best) t_best = t, face = 2 * a + 1;
        } else if (d[a] < -1e-12f) {
          const float t = (sc.room_min[a] - origin[a]) / d[a];
          if (t < t_best) t_best = t, face = 2 * a;
        }
      }
      if (face >= 0 && t_best > kNear) {
        const std::size_t i = static_cast<std::size_t>(v) * w + u;
        zbuf[i] = t_best;
        ids[i] = static_cast<std::int16_t>(face);
      }
    }
  }

  // Objects: exact ray tests inside each one's clipped, projected bounding box.
  static constexpr int kEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                        {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  const Eigen::Matrix3d world_to_cam = rot_d.transpose();
  for (std::size_t pi = 0; pi < sc.prims.size(); ++pi) {
    const Primitive& p = sc.prims[pi];
    Eigen::Vector3d pc[8];
    for (int i = 0; i < 8; ++i) pc[i] = world_to_cam * (p.corners[i] - origin_d);
    double umin = 1e30, umax = -1e30, vmin = 1e30, vmax = -1e30;
    bool any = false;
    const auto add = [&](const Eigen::Vector3d& q) {
      const double uu = fx * q.x() / q.z() + cx, vv = fy * q.y() / q.z() + cy;
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
    if (!any) continue;
    const int u0 = std::max(0, static_cast<int>(std::floor(umin)) - 1);
    const int u1 = std::min(w - 1, static_cast<int>(std::ceil(umax)) + 1);
    const int v0 = std::max(0, static_cast<int>(std::floor(vmin)) - 1);
    const int v1 = std::min(h - 1, static_cast<int>(std::ceil(vmax)) + 1);
    if (u0 > u1 || v0 > v1) continue;

    const auto id = static_cast<std::int16_t>(kRoomFaces + pi);
    const Vec3f o = ToLocal(p, origin - p.center);
    const Vec3f ld0 = ToLocal(p, d0), ldu = ToLocal(p, du), ldv = ToLocal(p, dv);
    for (int v = v0; v <= v1; ++v) {
      const Vec3f row = ld0 + static_cast<float>(v) * ldv;
      float* zrow = &zbuf[static_cast<std::size_t>(v) * w];
      std::int16_t* irow = &ids[static_cast<std::size_t>(v) * w];
      for (int u = u0; u <= u1; ++u) {
        const Vec3f d = row + static_cast<float>(u) * ldu;
        float t = -1.0f;
        switch (p.shape) {
          case SimShape::kBox: {
            float tmin = -std::numeric_limits<float>::infinity();
            float tmax = std::numeric_limits<float>::infinity();
            for (int a = 0; a < 3; ++a) {
              const float inv = 1.0f / d[a];  // +-inf for d[a] == 0 works with the slab test
              float t1 = (-p.half[a] - o[a]) * inv, t2 = (p.half[a] - o[a]) * inv;
              if (t1 > t2) std::swap(t1, t2);
              tmin = std::max(tmin, t1);
              tmax = std::min(tmax, t2);
            }
            if (tmin <= tmax && tmin > kNear) t = tmin;  // from inside: culled (back faces)
            break;
          }
          case SimShape::kCylinder: {
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
            // From inside the circle the side root is behind the camera, so `best` is a
            // cap or nothing; from inside the solid nothing is hit (culled).
            if (best < std::numeric_limits<float>::infinity()) t = best;
            break;
          }
          case SimShape::kSphere: {
            const float a = d.squaredNorm();
            const float b = o.dot(d);
            const float c = o.squaredNorm() - p.radius * p.radius;
            const float disc = b * b - a * c;
            if (c > 0.0f && disc >= 0.0f) {
              const float ts = (-b - std::sqrt(disc)) / a;
              if (ts > kNear) t = ts;
            }
            break;
          }
        }
        if (t > 0.0f && t < zrow[u]) {
          zrow[u] = t;
          irow[u] = id;
        }
      }
    }
  }

  // Deferred shading: every visible pixel is shaded exactly once.
  RgbdSample out;
  out.pose = camera_to_world;
  out.stamp = stamp;
  out.rgb.create(h, w, CV_8UC3);
  out.depth.create(h, w, CV_32FC1);
  const bool effects = sensor_.AnyEnabled();
  std::vector<float> incidence_cos(effects ? n : 0, 1.0f);
  for (int v = 0; v < h; ++v) {
    std::uint8_t* rgb_row = out.rgb.ptr<std::uint8_t>(v);
    float* depth_row = out.depth.ptr<float>(v);
    const Vec3f row = d0 + static_cast<float>(v) * dv;
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      const int id = ids[i];
      if (id < 0) {
        rgb_row[3 * u] = rgb_row[3 * u + 1] = rgb_row[3 * u + 2] = 0;
        depth_row[u] = 0.0f;
        continue;
      }
      const float t = zbuf[i];
      const Vec3f d = row + static_cast<float>(u) * du;
      const Vec3f hit = origin + t * d;
      Vec3f normal;
      float su = 0.0f, sv = 0.0f;
      int material = 0;
      if (id < kRoomFaces) {
        const int axis = id / 2;
        normal = Vec3f::Zero();
        normal[axis] = (id & 1) ? -1.0f : 1.0f;  // inward
        material = sc.face_material[id];
        if (axis == 0) {
          su = hit.y() - sc.room_min.y(), sv = hit.z();
        } else if (axis == 1) {
          su = hit.x() - sc.room_min.x(), sv = hit.z();
        } else {
          su = hit.x() - sc.room_min.x(), sv = hit.y() - sc.room_min.y();
        }
      } else {
        const Primitive& p = sc.prims[id - kRoomFaces];
        material = p.material;
        const Vec3f l = ToLocal(p, hit - p.center);
        switch (p.shape) {
          case SimShape::kBox: {
            const Vec3f r = l.cwiseAbs().cwiseQuotient(p.half);
            int a = 0;
            if (r.y() > r[a]) a = 1;
            if (r.z() > r[a]) a = 2;
            Vec3f ln = Vec3f::Zero();
            ln[a] = l[a] > 0.0f ? 1.0f : -1.0f;
            normal = ToWorld(p, ln);
            const int b = a == 0 ? 1 : 0, c = a == 2 ? 1 : 2;
            su = l[b] + p.half[b], sv = l[c] + p.half[c];
            break;
          }
          case SimShape::kCylinder:
            if (std::abs(std::abs(l.z()) - p.half.z()) < 1e-3f &&
                l.x() * l.x() + l.y() * l.y() < p.radius * p.radius * 0.998f) {
              normal = Vec3f(0.0f, 0.0f, l.z() > 0.0f ? 1.0f : -1.0f);
              su = l.x(), sv = l.y();
            } else {
              normal = Vec3f(l.x(), l.y(), 0.0f) / p.radius;
              su = std::atan2(l.y(), l.x()) * p.radius, sv = l.z() + p.half.z();
            }
            break;
          case SimShape::kSphere:
            normal = l / p.radius;
            su = std::atan2(normal.y(), normal.x()) * p.radius;
            sv = std::asin(std::clamp(normal.z(), -1.0f, 1.0f)) * p.radius;
            break;
        }
      }
      float albedo[3];
      sc.samplers[material].Sample(su, sv, albedo);
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
      for (int k = 0; k < 3; ++k) {
        const float c = albedo[k] * light[k] * 255.0f + 0.5f;
        rgb_row[3 * u + k] = static_cast<std::uint8_t>(c < 0.0f ? 0.0f : (c > 255.0f ? 255.0f : c));
      }
      depth_row[u] = t;
      if (effects) incidence_cos[i] = std::abs(normal.dot(d)) / d.norm();
    }
  }

  if (effects) {
    // One generator per frame, seeded from the options' seed and the exact pose and camera:
    // the same inputs give the same noise, different poses give independent noise.
    std::uint64_t key = Mix64(sensor_.seed + 0x1234567ull);
    if (stamped) {
      std::uint64_t bits;
      std::memcpy(&bits, &stamp, sizeof bits);
      key = Mix64(key ^ bits ^ 0x5851f42d4c957f2dull);
    }
    const Vector7d v7 = camera_to_world.ToVector7();
    for (int k = 0; k < 7; ++k) {
      std::uint64_t bits;
      std::memcpy(&bits, &v7[k], sizeof bits);
      key = Mix64(key ^ bits);
    }
    key = Mix64(key ^ (static_cast<std::uint64_t>(w) << 32 | static_cast<std::uint64_t>(h)));
    const float cos_graze =
        sensor_.grazing_angle_deg > 0.0
            ? static_cast<float>(std::cos(sensor_.grazing_angle_deg * M_PI / 180.0))
            : -1.0f;
    const auto rgb_sigma = static_cast<float>(sensor_.rgb_noise_sigma);
    const auto dropout = static_cast<float>(sensor_.depth_dropout);
    for (int v = 0; v < h; ++v) {
      float* depth_row = out.depth.ptr<float>(v);
      std::uint8_t* rgb_row = out.rgb.ptr<std::uint8_t>(v);
      for (int u = 0; u < w; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * w + u;
        // Counter-based randomness: two 64-bit hashes per pixel, no generator state, the same
        // numbers on every platform and standard library.
        const std::uint64_t r1 = Mix64(key + 2 * i), r2 = Mix64(key + 2 * i + 1);
        float z = depth_row[u];
        if (z > 0.0f) {
          if ((sensor_.max_range > 0.0 && z > sensor_.max_range) ||
              (sensor_.min_range > 0.0 && z < sensor_.min_range) || incidence_cos[i] < cos_graze) {
            z = 0.0f;
          } else if (dropout > 0.0f && Uniform16(r2 >> 48) < dropout) {
            z = 0.0f;
          } else if (sensor_.depth_noise_sigma > 0.0 || sensor_.depth_noise_quadratic > 0.0) {
            const float sigma = static_cast<float>(sensor_.depth_noise_sigma +
                                                   sensor_.depth_noise_quadratic * z * z);
            z = std::max(0.0f, z + sigma * Gaussian4(r1));
          }
          depth_row[u] = z;
        }
        if (rgb_sigma > 0.0f) {
          for (int k = 0; k < 3; ++k) {
            const float noise = rgb_sigma * Gaussian4(Mix64(r2 + 0x9e3779b97f4a7c15ull * (k + 1)));
            const float c = rgb_row[3 * u + k] + noise + 0.5f;
            rgb_row[3 * u + k] =
                static_cast<std::uint8_t>(c < 0.0f ? 0.0f : (c > 255.0f ? 255.0f : c));
          }
        }
      }
    }
  }
  return out;
}

}  // namespace p2i::scene
