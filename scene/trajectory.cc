/// @file trajectory.cc
/// @brief Arm sweeps, adjacent sweeps, orbits and bounded random walks.
#include "scene/trajectory.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "scene/sim_scene.h"
#include "scene/strict_yaml_reader.h"

namespace p2i::scene {
namespace {

constexpr double kDeg = M_PI / 180.0;

double WrapPi(double a) {
  while (a > M_PI) a -= 2 * M_PI;
  while (a < -M_PI) a += 2 * M_PI;
  return a;
}

void CheckRate(double rate_hz) {
  if (!(rate_hz > 0.0 && rate_hz <= 1000.0)) {
    throw std::invalid_argument("rate_hz must be in (0, 1000]");
  }
}

void CheckPositive(double v, const char* name) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    throw std::invalid_argument(std::string(name) + " must be a positive number");
  }
}

/// Options parsing and validation with the source named on failure.
template <typename Options, typename Fill>
Options Parse(const YAML::Node& node, const std::string& source, const std::string& what,
              std::set<std::string> keys, bool allow_type, Fill fill) {
  const StrictYamlReader r(source);
  // GenerateTrajectoriesFromYaml passes the whole map, `type` included (copying the node
  // without it would lose the line numbers for error messages).
  if (allow_type) keys.insert("type");
  r.CheckKeys(node, keys, what);
  Options o;
  fill(r, &o);
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    r.Fail(node, what + ": " + e.what());
  }
  return o;
}

}  // namespace

Pose LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = target - eye;
  if (!(z.norm() > 1e-12)) throw std::invalid_argument("LookAt: eye and target coincide");
  const Eigen::Vector3d zc = z.normalized();
  const Eigen::Vector3d x = zc.cross(up);
  if (!(x.norm() > 1e-9)) throw std::invalid_argument("LookAt: view direction parallel to up");
  const Eigen::Vector3d xc = x.normalized();
  const Eigen::Vector3d yc = zc.cross(xc);
  Eigen::Matrix3d r;
  r.col(0) = xc;
  r.col(1) = yc;
  r.col(2) = zc;
  return Pose(eye, Eigen::Quaterniond(r));
}

Pose LookYawPitch(const Eigen::Vector3d& eye, double yaw_deg, double pitch_deg) {
  const double y = yaw_deg * kDeg, p = pitch_deg * kDeg;
  const Eigen::Vector3d f(std::cos(p) * std::cos(y), std::cos(p) * std::sin(y), std::sin(p));
  return LookAt(eye, eye + f);
}

// ---------------------------------------------------------------- arm sweep

static ArmSweepOptions ParseArmSweepOptions(const YAML::Node& node, const std::string& source,
                                            bool allow_type) {
  return Parse<ArmSweepOptions>(node, source, "arm_sweep",
                                {"base", "reach", "center_yaw_deg", "arc_deg", "heights",
                                 "pitch_deg", "speed", "rate_hz", "start_time"},
                                allow_type, [&](const StrictYamlReader& r, ArmSweepOptions* o) {
                                  r.OptionalVec3(node, "base", "arm_sweep", &o->base);
                                  r.OptionalDouble(node, "reach", "arm_sweep", &o->reach);
                                  r.OptionalDouble(node, "center_yaw_deg", "arm_sweep",
                                                   &o->center_yaw_deg);
                                  r.OptionalDouble(node, "arc_deg", "arm_sweep", &o->arc_deg);
                                  r.OptionalDouble(node, "pitch_deg", "arm_sweep", &o->pitch_deg);
                                  r.OptionalDouble(node, "speed", "arm_sweep", &o->speed);
                                  r.OptionalDouble(node, "rate_hz", "arm_sweep", &o->rate_hz);
                                  r.OptionalDouble(node, "start_time", "arm_sweep", &o->start_time);
                                  if (node["heights"]) {
                                    const YAML::Node h = node["heights"];
                                    if (!h.IsSequence())
                                      r.Fail(h, "arm_sweep.heights must be a list of numbers");
                                    o->heights.clear();
                                    for (const auto& v : h)
                                      o->heights.push_back(r.Double(v, "arm_sweep.heights"));
                                  }
                                });
}

ArmSweepOptions ArmSweepOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  return ParseArmSweepOptions(node, source, false);
}

void ArmSweepOptions::Validate() const {
  if (!base.allFinite()) throw std::invalid_argument("base must be finite");
  CheckPositive(reach, "reach");
  if (!(arc_deg > 0.0 && arc_deg <= 360.0))
    throw std::invalid_argument("arc_deg must be in (0, 360]");
  if (heights.empty()) throw std::invalid_argument("heights must list at least one height");
  for (double h : heights) {
    if (!std::isfinite(h)) throw std::invalid_argument("heights must be finite");
  }
  if (!(std::abs(pitch_deg) < 89.0)) throw std::invalid_argument("pitch_deg must be in (-89, 89)");
  if (!std::isfinite(center_yaw_deg) || !std::isfinite(start_time)) {
    throw std::invalid_argument("center_yaw_deg and start_time must be finite");
  }
  CheckPositive(speed, "speed");
  CheckRate(rate_hz);
}

std::vector<StampedPose> GenerateArmSweep(const ArmSweepOptions& o) {
  o.Validate();
  // The path is a chain of segments (arcs at each height joined by vertical moves), sampled at
  // equal arc length so the camera moves at constant speed.
  struct Segment {
    bool arc;
    double yaw0, yaw1;  // radians
    double z0, z1;
    double length;
  };
  const double half = o.arc_deg * kDeg / 2.0;
  const double c = o.center_yaw_deg * kDeg;
  std::vector<Segment> segments;
  for (std::size_t i = 0; i < o.heights.size(); ++i) {
    const bool forward = i % 2 == 0;
    const double y0 = forward ? c - half : c + half, y1 = forward ? c + half : c - half;
    if (i > 0) {
      const double zp = o.heights[i - 1], zn = o.heights[i];
      segments.push_back({false, y0, y0, zp, zn, std::abs(zn - zp)});
    }
    segments.push_back({true, y0, y1, o.heights[i], o.heights[i], o.reach * 2.0 * half});
  }
  double total = 0.0;
  for (const auto& s : segments) total += s.length;
  const double step = o.speed / o.rate_hz;
  const auto n = static_cast<std::size_t>(std::floor(total / step + 1e-9)) + 1;
  std::vector<StampedPose> out;
  out.reserve(n);
  std::size_t seg = 0;
  double seg_start = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double s = std::min(total, k * step);
    while (seg + 1 < segments.size() && s > seg_start + segments[seg].length) {
      seg_start += segments[seg].length;
      ++seg;
    }
    const Segment& g = segments[seg];
    const double a = g.length > 0.0 ? std::clamp((s - seg_start) / g.length, 0.0, 1.0) : 1.0;
    const double yaw = g.yaw0 + a * (g.yaw1 - g.yaw0);
    const double z = g.z0 + a * (g.z1 - g.z0);
    const Eigen::Vector3d eye(o.base.x() + o.reach * std::cos(yaw),
                              o.base.y() + o.reach * std::sin(yaw), z);
    out.push_back({o.start_time + k / o.rate_hz, LookYawPitch(eye, yaw / kDeg, o.pitch_deg)});
  }
  return out;
}

// ---------------------------------------------------------------- adjacent sweeps

static AdjacentSweepsOptions ParseAdjacentSweepsOptions(const YAML::Node& node,
                                                        const std::string& source,
                                                        bool allow_type) {
  return Parse<AdjacentSweepsOptions>(
      node, source, "adjacent_sweeps", {"sweep", "count", "offset", "axis"}, allow_type,
      [&](const StrictYamlReader& r, AdjacentSweepsOptions* o) {
        if (node["sweep"]) o->sweep = ArmSweepOptions::FromYaml(node["sweep"], source);
        if (node["count"]) {
          const double c = r.Double(node["count"], "adjacent_sweeps.count");
          if (c != std::floor(c)) r.Fail(node["count"], "adjacent_sweeps.count must be an integer");
          o->count = static_cast<int>(c);
        }
        r.OptionalDouble(node, "offset", "adjacent_sweeps", &o->offset);
        if (node["axis"]) {
          const std::string a = r.String(node["axis"], "adjacent_sweeps.axis");
          if (a == "radial") {
            o->axis = AdjacentSweepsOptions::Axis::kRadial;
          } else if (a == "vertical") {
            o->axis = AdjacentSweepsOptions::Axis::kVertical;
          } else {
            r.Fail(node["axis"], "adjacent_sweeps.axis must be radial or vertical");
          }
        }
      });
}

AdjacentSweepsOptions AdjacentSweepsOptions::FromYaml(const YAML::Node& node,
                                                      const std::string& source) {
  return ParseAdjacentSweepsOptions(node, source, false);
}

void AdjacentSweepsOptions::Validate() const {
  sweep.Validate();
  if (count < 1 || count > 1000) throw std::invalid_argument("count must be in [1, 1000]");
  if (!std::isfinite(offset)) throw std::invalid_argument("offset must be finite");
  if (axis == Axis::kRadial && !(sweep.reach + (count - 1) * offset > 0.0)) {
    throw std::invalid_argument("offset makes the reach of the last sweep non-positive");
  }
}

std::vector<std::vector<StampedPose>> GenerateAdjacentSweeps(const AdjacentSweepsOptions& o) {
  o.Validate();
  std::vector<std::vector<StampedPose>> out;
  for (int i = 0; i < o.count; ++i) {
    ArmSweepOptions s = o.sweep;
    if (o.axis == AdjacentSweepsOptions::Axis::kRadial) {
      s.reach += i * o.offset;
    } else {
      for (double& h : s.heights) h += i * o.offset;
    }
    out.push_back(GenerateArmSweep(s));
  }
  return out;
}

// ---------------------------------------------------------------- orbit

static OrbitOptions ParseOrbitOptions(const YAML::Node& node, const std::string& source,
                                      bool allow_type) {
  return Parse<OrbitOptions>(node, source, "orbit",
                             {"center", "radius", "height", "revolutions", "start_angle_deg",
                              "speed", "rate_hz", "start_time"},
                             allow_type, [&](const StrictYamlReader& r, OrbitOptions* o) {
                               r.OptionalVec3(node, "center", "orbit", &o->center);
                               r.OptionalDouble(node, "radius", "orbit", &o->radius);
                               r.OptionalDouble(node, "height", "orbit", &o->height);
                               r.OptionalDouble(node, "revolutions", "orbit", &o->revolutions);
                               r.OptionalDouble(node, "start_angle_deg", "orbit",
                                                &o->start_angle_deg);
                               r.OptionalDouble(node, "speed", "orbit", &o->speed);
                               r.OptionalDouble(node, "rate_hz", "orbit", &o->rate_hz);
                               r.OptionalDouble(node, "start_time", "orbit", &o->start_time);
                             });
}

OrbitOptions OrbitOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  return ParseOrbitOptions(node, source, false);
}

void OrbitOptions::Validate() const {
  if (!center.allFinite()) throw std::invalid_argument("center must be finite");
  CheckPositive(radius, "radius");
  CheckPositive(revolutions, "revolutions");
  CheckPositive(speed, "speed");
  CheckRate(rate_hz);
  if (!std::isfinite(height) || !std::isfinite(start_angle_deg) || !std::isfinite(start_time)) {
    throw std::invalid_argument("height, start_angle_deg and start_time must be finite");
  }
}

std::vector<StampedPose> GenerateOrbit(const OrbitOptions& o) {
  o.Validate();
  const double total_angle = 2 * M_PI * o.revolutions;
  const double dangle = o.speed / o.rate_hz / o.radius;
  const auto n = static_cast<std::size_t>(std::floor(total_angle / dangle + 1e-9)) + 1;
  std::vector<StampedPose> out;
  out.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double a = o.start_angle_deg * kDeg + std::min(total_angle, k * dangle);
    const Eigen::Vector3d eye(o.center.x() + o.radius * std::cos(a),
                              o.center.y() + o.radius * std::sin(a), o.height);
    out.push_back({o.start_time + k / o.rate_hz, LookAt(eye, o.center)});
  }
  return out;
}

// ---------------------------------------------------------------- random walk

static RandomWalkOptions ParseRandomWalkOptions(const YAML::Node& node, const std::string& source,
                                                bool allow_type) {
  return Parse<RandomWalkOptions>(
      node, source, "random_walk",
      {"duration", "speed", "max_turn_rate_deg", "wall_margin", "clearance", "min_height",
       "max_height", "seed", "rate_hz", "start_time"},
      allow_type, [&](const StrictYamlReader& r, RandomWalkOptions* o) {
        r.OptionalDouble(node, "duration", "random_walk", &o->duration);
        r.OptionalDouble(node, "speed", "random_walk", &o->speed);
        r.OptionalDouble(node, "max_turn_rate_deg", "random_walk", &o->max_turn_rate_deg);
        r.OptionalDouble(node, "wall_margin", "random_walk", &o->wall_margin);
        r.OptionalDouble(node, "clearance", "random_walk", &o->clearance);
        r.OptionalDouble(node, "min_height", "random_walk", &o->min_height);
        r.OptionalDouble(node, "max_height", "random_walk", &o->max_height);
        r.OptionalDouble(node, "rate_hz", "random_walk", &o->rate_hz);
        r.OptionalDouble(node, "start_time", "random_walk", &o->start_time);
        if (node["seed"]) {
          const double s = r.Double(node["seed"], "random_walk.seed");
          if (s < 0 || s != std::floor(s) || s > 4294967295.0) {
            r.Fail(node["seed"], "random_walk.seed must be a non-negative 32-bit integer");
          }
          o->seed = static_cast<std::uint32_t>(s);
        }
      });
}

RandomWalkOptions RandomWalkOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  return ParseRandomWalkOptions(node, source, false);
}

void RandomWalkOptions::Validate() const {
  CheckPositive(duration, "duration");
  CheckPositive(speed, "speed");
  CheckPositive(max_turn_rate_deg, "max_turn_rate_deg");
  CheckRate(rate_hz);
  if (!(wall_margin >= 0.0) || !(clearance >= 0.0)) {
    throw std::invalid_argument("wall_margin and clearance must be >= 0");
  }
  if (!(min_height < max_height))
    throw std::invalid_argument("min_height must be below max_height");
  if (!std::isfinite(start_time)) throw std::invalid_argument("start_time must be finite");
}

std::vector<StampedPose> GenerateRandomWalk(const RandomWalkOptions& o, const SimScene& scene) {
  o.Validate();
  const SimBounds room = scene.Bounds();
  const Eigen::Vector3d lo(room.min.x() + o.wall_margin, room.min.y() + o.wall_margin,
                           std::max(room.min.z() + o.wall_margin, o.min_height));
  const Eigen::Vector3d hi(room.max.x() - o.wall_margin, room.max.y() - o.wall_margin,
                           std::min(room.max.z() - o.wall_margin, o.max_height));
  if ((hi - lo).minCoeff() <= 0.0) {
    throw std::runtime_error(
        "random walk: the room minus wall_margin and the height limits "
        "leave no space; lower wall_margin or widen min/max_height");
  }
  const auto ok = [&](const Eigen::Vector3d& p) {
    return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all() &&
           scene.IsFree(p, o.clearance);
  };
  const Eigen::Vector3d centre = (lo + hi) / 2.0;
  // Start at the free point nearest the centre (search outward on a grid).
  Eigen::Vector3d p = centre;
  bool found = ok(p);
  for (double r = 0.1; !found && r < (hi - lo).maxCoeff(); r += 0.1) {
    for (int k = 0; k < 32 && !found; ++k) {
      const double a = 2 * M_PI * k / 32;
      const Eigen::Vector3d q = centre + r * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
      if (ok(q)) p = q, found = true;
    }
  }
  if (!found) throw std::runtime_error("random walk: no free start point in the scene");

  std::mt19937 rng(o.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const double dt = 1.0 / o.rate_hz;
  const double step = o.speed * dt;
  const double max_turn = o.max_turn_rate_deg * kDeg * dt;  // per step
  // Heading of motion (yaw, climb) and gaze (yaw, pitch) drift smoothly and independently.
  double heading = std::atan2(centre.y() - room.min.y(), centre.x() - room.min.x());
  double climb = 0.0;
  double gaze_yaw = uniform(rng) * M_PI, gaze_pitch = 0.0;
  double gaze_rate = 0.0, pitch_rate = 0.0;
  const auto n = static_cast<std::size_t>(std::floor(o.duration * o.rate_hz)) + 1;
  std::vector<StampedPose> out;
  out.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    out.push_back({o.start_time + k * dt, LookYawPitch(p, gaze_yaw / kDeg, gaze_pitch / kDeg)});
    // Move: keep the heading while the step stays free, else pick a new one that is.
    heading += 0.15 * gauss(rng);
    climb = std::clamp(climb + 0.05 * gauss(rng), -0.4, 0.4);
    Eigen::Vector3d d(std::cos(climb) * std::cos(heading), std::cos(climb) * std::sin(heading),
                      std::sin(climb));
    if (!ok(p + step * d)) {
      bool moved = false;
      const double to_centre = std::atan2(centre.y() - p.y(), centre.x() - p.x());
      for (int attempt = 0; attempt < 64 && !moved; ++attempt) {
        // Early attempts aim roughly at the centre, later ones anywhere.
        const double spread = attempt < 16 ? M_PI / 3 : M_PI;
        heading = to_centre + spread * uniform(rng);
        climb = 0.3 * uniform(rng) + (centre.z() - p.z() > 0 ? 0.1 : -0.1);
        d = Eigen::Vector3d(std::cos(climb) * std::cos(heading),
                            std::cos(climb) * std::sin(heading), std::sin(climb));
        moved = ok(p + step * d);
      }
      if (!moved) d.setZero();  // boxed in: wait for a free direction rather than cross an object
    }
    p += step * d;
    // Gaze: a smoothly varying turn rate, bounded; steered inward when it points away from
    // the room centre (more than 60 degrees off) so views keep looking into the room.
    const double inward = std::atan2(centre.y() - p.y(), centre.x() - p.x());
    const double off = WrapPi(gaze_yaw - inward);
    const double far_from_centre = (p - centre).head<2>().norm();
    gaze_rate = std::clamp(0.9 * gaze_rate + 0.3 * max_turn * gauss(rng), -max_turn, max_turn);
    if (far_from_centre > 0.5 && std::abs(off) > M_PI / 3)
      gaze_rate = off > 0 ? -max_turn : max_turn;
    gaze_yaw = WrapPi(gaze_yaw + gaze_rate);
    pitch_rate = std::clamp(0.9 * pitch_rate + 0.3 * max_turn * gauss(rng), -max_turn, max_turn);
    if (std::abs(gaze_pitch) > 20 * kDeg) pitch_rate = gaze_pitch > 0 ? -max_turn : max_turn;
    gaze_pitch += pitch_rate;
  }
  return out;
}

// ---------------------------------------------------------------- YAML entry point

std::vector<std::vector<StampedPose>> GenerateTrajectoriesFromYaml(const YAML::Node& node,
                                                                   const std::string& source,
                                                                   const SimScene* scene) {
  const StrictYamlReader r(source);
  r.CheckMap(node, "trajectory");
  const std::string type = r.String(r.Require(node, "type", "trajectory"), "trajectory.type");
  if (type == "arm_sweep") return {GenerateArmSweep(ParseArmSweepOptions(node, source, true))};
  if (type == "adjacent_sweeps") {
    return GenerateAdjacentSweeps(ParseAdjacentSweepsOptions(node, source, true));
  }
  if (type == "orbit") return {GenerateOrbit(ParseOrbitOptions(node, source, true))};
  if (type == "random_walk") {
    if (scene == nullptr) throw std::invalid_argument("random_walk trajectories need a scene");
    return {GenerateRandomWalk(ParseRandomWalkOptions(node, source, true), *scene)};
  }
  r.Fail(node["type"], "unknown trajectory type '" + type +
                           "' (use arm_sweep, adjacent_sweeps, orbit or random_walk)");
}

}  // namespace p2i::scene
