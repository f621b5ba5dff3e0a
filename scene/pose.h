/// @file pose.h
/// @brief Rigid camera pose (camera-to-world), the 7-d vector P2I-NET is conditioned on.
#pragma once

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace p2i::scene {

using Vector7d = Eigen::Matrix<double, 7, 1>;

/// A rigid transform (rotation + translation in metres), by convention camera-to-world.
/// The quaternion is kept unit-norm with the canonical sign qw >= 0, so the 7-d vector
/// (tx ty tz qx qy qz qw) of a pose is unique. This class is a value type: thread-compatible.
class Pose {
 public:
  /// The identity.
  Pose();
  /// `q` need not be normalised; it must have a non-zero, finite norm (else std::invalid_argument).
  Pose(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation);

  /// From a 4x4 homogeneous matrix; the rotation block is re-orthonormalised. Throws
  /// std::invalid_argument when the last row is not (0 0 0 1) or values are not finite.
  static Pose FromMatrix(const Eigen::Matrix4d& m);
  /// From (tx ty tz qx qy qz qw), scalar last like TUM.
  static Pose FromVector7(const Vector7d& v);
  /// Parses one TUM trajectory line "timestamp tx ty tz qx qy qz qw". Throws
  /// std::invalid_argument naming the problem when the line is malformed.
  static Pose FromTumLine(const std::string& line, double* stamp);
  static Pose Identity() { return Pose(); }

  Eigen::Matrix4d ToMatrix() const;
  Vector7d ToVector7() const;
  /// "timestamp tx ty tz qx qy qz qw" with enough digits to round-trip.
  std::string ToTumLine(double stamp) const;

  const Eigen::Vector3d& translation() const { return t_; }
  const Eigen::Quaterniond& rotation() const { return q_; }
  /// The camera's optical axis (+z of the camera frame) in the parent frame.
  Eigen::Vector3d Forward() const { return q_ * Eigen::Vector3d::UnitZ(); }

  Pose operator*(const Pose& other) const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const { return q_ * point + t_; }
  Pose Inverse() const;

  /// Distances between two poses: translation in metres, rotation angle in degrees [0, 180].
  static double TranslationDistance(const Pose& a, const Pose& b);
  static double RotationDistanceDeg(const Pose& a, const Pose& b);

  /// Linear interpolation of translation and SLERP of rotation; alpha in [0, 1].
  static Pose Interpolate(const Pose& a, const Pose& b, double alpha);

  /// GTSAM-style helpers for tests.
  void print(const std::string& label = "") const;
  bool equals(const Pose& other, double tol = 1e-9) const;

 private:
  void Canonicalize();

  Eigen::Vector3d t_;
  Eigen::Quaterniond q_;
};

std::ostream& operator<<(std::ostream& os, const Pose& pose);

struct StampedPose {
  double stamp = 0.0;  ///< seconds
  Pose pose;
};

/// The pose at `stamp` on a trajectory sorted by time: SLERP between the two neighbours.
/// Returns nullopt outside the trajectory's time range or when the bracketing poses are more than
/// `max_gap` seconds apart.
std::optional<Pose> InterpolateAt(const std::vector<StampedPose>& trajectory, double stamp,
                                  double max_gap = 1e9);

}  // namespace p2i::scene
