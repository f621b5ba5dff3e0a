#include "scene/pose.h"

#include <cmath>

#include <catch2/catch.hpp>

using p2i::scene::InterpolateAt;
using p2i::scene::Pose;
using p2i::scene::StampedPose;
using p2i::scene::Vector7d;

namespace {

Pose MakePose(double tx, double ty, double tz, double angle_deg, Eigen::Vector3d axis) {
  return Pose(Eigen::Vector3d(tx, ty, tz),
              Eigen::Quaterniond(Eigen::AngleAxisd(angle_deg * M_PI / 180.0, axis.normalized())));
}

}  // namespace

TEST_CASE("Pose round-trips through matrix, 7-vector and TUM line", "[unit]") {
  const Pose p = MakePose(1.5, -0.25, 3.0, 37.0, Eigen::Vector3d(0.2, 1.0, -0.3));
  CHECK(Pose::FromMatrix(p.ToMatrix()).equals(p, 1e-12));
  CHECK(Pose::FromVector7(p.ToVector7()).equals(p, 1e-12));
  double stamp = 0;
  const Pose q = Pose::FromTumLine(p.ToTumLine(12.5), &stamp);
  CHECK(stamp == Approx(12.5));
  CHECK(q.equals(p, 1e-8));
}

TEST_CASE("Pose keeps a unit quaternion with qw >= 0", "[unit]") {
  Vector7d v;
  v << 0, 0, 0, 0.0, 0.0, 2.0 * std::sin(0.3), -2.0 * std::cos(0.3);  // norm 2, qw < 0
  const Pose p = Pose::FromVector7(v);
  CHECK(p.rotation().norm() == Approx(1.0));
  CHECK(p.rotation().w() >= 0.0);
  CHECK(p.ToVector7()(6) == Approx(std::cos(0.3)));
  CHECK(p.ToVector7()(5) == Approx(-std::sin(0.3)));
  CHECK_THROWS_AS(Pose::FromVector7(Vector7d::Zero()), std::invalid_argument);
}

TEST_CASE("Pose composition and inverse", "[unit]") {
  const Pose a = MakePose(1, 2, 3, 90, Eigen::Vector3d::UnitZ());
  const Pose b = MakePose(1, 0, 0, 0, Eigen::Vector3d::UnitZ());
  const Pose ab = a * b;
  // Rotating (1,0,0) by 90 deg about z gives (0,1,0); plus a's translation.
  CHECK(ab.translation().isApprox(Eigen::Vector3d(1, 3, 3), 1e-12));
  CHECK((a * a.Inverse()).equals(Pose::Identity(), 1e-12));
  CHECK((a * Eigen::Vector3d(1, 0, 0)).isApprox(Eigen::Vector3d(1, 3, 3), 1e-12));
  CHECK(ab.ToMatrix().isApprox(a.ToMatrix() * b.ToMatrix(), 1e-12));
}

TEST_CASE("Pose distances", "[unit]") {
  const Pose a = MakePose(0, 0, 0, 10, Eigen::Vector3d::UnitY());
  const Pose b = MakePose(3, 4, 0, 40, Eigen::Vector3d::UnitY());
  CHECK(Pose::TranslationDistance(a, b) == Approx(5.0));
  CHECK(Pose::RotationDistanceDeg(a, b) == Approx(30.0));
  CHECK(Pose::RotationDistanceDeg(a, a) == Approx(0.0).margin(1e-6));
}

TEST_CASE("Pose SLERP interpolation between timestamps", "[unit]") {
  const Pose a = MakePose(0, 0, 0, 0, Eigen::Vector3d::UnitX());
  const Pose b = MakePose(2, 0, 0, 90, Eigen::Vector3d::UnitX());
  std::vector<StampedPose> traj{{1.0, a}, {2.0, b}};
  auto mid = InterpolateAt(traj, 1.5);
  REQUIRE(mid.has_value());
  CHECK(mid->translation().isApprox(Eigen::Vector3d(1, 0, 0)));
  CHECK(Pose::RotationDistanceDeg(*mid, a) == Approx(45.0));
  CHECK_FALSE(InterpolateAt(traj, 0.5).has_value());
  CHECK_FALSE(InterpolateAt(traj, 1.5, /*max_gap=*/0.5).has_value());
  CHECK(InterpolateAt(traj, 2.0)->equals(b, 1e-12));
}

TEST_CASE("Pose rejects malformed input", "[unit]") {
  CHECK_THROWS_AS(Pose::FromTumLine("1.0 2 3", nullptr), std::invalid_argument);
  CHECK_THROWS_AS(Pose::FromTumLine("1.0 0 0 0 0 0 0 1 7", nullptr), std::invalid_argument);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(3, 0) = 1;
  CHECK_THROWS_AS(Pose::FromMatrix(m), std::invalid_argument);
  m = Eigen::Matrix4d::Identity();
  m(0, 0) = -1;  // reflection
  CHECK_THROWS_AS(Pose::FromMatrix(m), std::invalid_argument);
}
