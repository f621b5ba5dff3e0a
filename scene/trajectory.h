/// @file trajectory.h
/// @brief Camera trajectory generators for the synthetic scene: robot-arm sweeps like the P2I-NET
/// capture rig, adjacent sweeps, orbits and a bounded random walk. All return camera-to-world
/// poses (OpenCV camera axes, world z up) stamped at a fixed rate.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "scene/pose.h"

namespace YAML {
class Node;
}

namespace p2i::scene {

class SimScene;

/// A camera at `eye` looking at `target` with the image's "up" towards `up` (world z by
/// default): camera x right, y down, z forward. Throws std::invalid_argument when eye == target
/// or the view direction is parallel to `up`.
Pose LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
            const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

/// A camera at `eye` looking towards yaw (from +x about +z) and pitch (up positive), degrees.
Pose LookYawPitch(const Eigen::Vector3d& eye, double yaw_deg, double pitch_deg);

/// A robot arm with a fixed base moves the camera along horizontal arcs (radius `reach` around
/// the base's vertical axis), one arc per height, alternating direction, with vertical moves
/// between heights. The camera looks radially outward from the base (into the room), tilted by
/// `pitch_deg`. Defaults fit both built-in offices.
struct ArmSweepOptions {
  Eigen::Vector3d base{0.0, -1.6, 0.0};  ///< base position (m); z is ignored (heights are absolute)
  double reach = 0.5;                    ///< arc radius (m)
  double center_yaw_deg = 90.0;          ///< direction of the middle of the arc, from +x about +z
  double arc_deg = 120.0;                ///< angular extent of each arc
  std::vector<double> heights{1.0, 1.3, 1.6};  ///< camera heights above the floor (m)
  double pitch_deg = -10.0;                    ///< camera tilt, negative looks down
  double speed = 0.15;                         ///< camera speed along the path (m/s)
  double rate_hz = 20.0;                       ///< pose rate; the paper's videos are 20 frames/s
  double start_time = 0.0;                     ///< stamp of the first pose (s)

  /// Keys are the field names; base is [x, y, z], heights a list. Unknown keys are errors
  /// naming `source`, line and key (std::runtime_error).
  static ArmSweepOptions FromYaml(const YAML::Node& node, const std::string& source);
  /// Throws std::invalid_argument saying which value is out of range.
  void Validate() const;
};

/// Several arm sweeps, each displaced from the previous by `offset` metres: for the paper's
/// setting (b) (train on one trajectory, test on the adjacent one).
struct AdjacentSweepsOptions {
  enum class Axis { kRadial, kVertical };
  ArmSweepOptions sweep;      ///< the first sweep
  int count = 3;              ///< number of trajectories
  double offset = 0.1;        ///< distance between neighbouring trajectories (m)
  Axis axis = Axis::kRadial;  ///< radial: reach grows by offset; vertical: heights rise by offset

  /// Keys: sweep (an ArmSweepOptions map), count, offset, axis (radial|vertical).
  static AdjacentSweepsOptions FromYaml(const YAML::Node& node, const std::string& source);
  void Validate() const;
};

/// The camera circles `center` at `radius` (horizontal circle at height `height`) looking at
/// `center`, at constant speed.
struct OrbitOptions {
  Eigen::Vector3d center{0.0, 0.0, 1.0};  ///< the point looked at (m)
  double radius = 0.8;                    ///< m
  double height = 1.3;                    ///< camera height (m)
  double revolutions = 1.0;
  double start_angle_deg = 0.0;  ///< from +x about +z
  double speed = 0.2;            ///< m/s along the circle
  double rate_hz = 20.0;
  double start_time = 0.0;

  static OrbitOptions FromYaml(const YAML::Node& node, const std::string& source);
  void Validate() const;
};

/// A smooth, seeded random walk that stays inside the room (by `wall_margin`), between
/// `min_height` and `max_height`, away from objects (by `clearance`), moving at `speed` and
/// turning its gaze at most `max_turn_rate_deg` per second, steered to keep looking into the room.
struct RandomWalkOptions {
  double duration = 30.0;           ///< s
  double speed = 0.2;               ///< m/s (every step has exactly this length unless blocked)
  double max_turn_rate_deg = 30.0;  ///< deg/s, gaze yaw and pitch
  double wall_margin = 0.5;         ///< m from walls
  double clearance = 0.3;           ///< m from objects
  double min_height = 0.8;          ///< m
  double max_height = 1.8;          ///< m
  std::uint32_t seed = 0;
  double rate_hz = 20.0;
  double start_time = 0.0;

  static RandomWalkOptions FromYaml(const YAML::Node& node, const std::string& source);
  void Validate() const;
};

std::vector<StampedPose> GenerateArmSweep(const ArmSweepOptions& options);
std::vector<std::vector<StampedPose>> GenerateAdjacentSweeps(const AdjacentSweepsOptions& options);
std::vector<StampedPose> GenerateOrbit(const OrbitOptions& options);
/// Starts at the free point nearest the room centre at mid height. Throws std::runtime_error
/// when the scene has no free space within the bounds.
std::vector<StampedPose> GenerateRandomWalk(const RandomWalkOptions& options,
                                            const SimScene& scene);

/// One YAML entry point for tools and nodes: a map with `type` (arm_sweep, adjacent_sweeps,
/// orbit, random_walk) plus that generator's keys. Returns one trajectory, or `count` for
/// adjacent_sweeps. random_walk needs `scene` (std::invalid_argument when null).
std::vector<std::vector<StampedPose>> GenerateTrajectoriesFromYaml(const YAML::Node& node,
                                                                   const std::string& source,
                                                                   const SimScene* scene);

}  // namespace p2i::scene
