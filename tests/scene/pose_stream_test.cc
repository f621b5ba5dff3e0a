/// @file pose_stream_test.cc
/// @brief scene::PoseStream: exact interpolated values, out-of-order and duplicate stamps,
/// tolerance edges, capacity.
#include <cmath>

#include <catch2/catch.hpp>

#include "scene/pose_stream.h"

namespace p2i::scene {
namespace {

constexpr int64_t kMs = 1'000'000;

Pose YawPose(double x, double y, double z, double yaw_rad) {
  return Pose(Eigen::Vector3d(x, y, z),
              Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ())));
}

TEST_CASE("PoseStream interpolates between the bracketing poses with exact values", "[unit]") {
  PoseStream stream(16);
  REQUIRE(stream.Add(1000 * kMs, YawPose(0, 0, 0, 0)) == PoseStream::AddResult::kAdded);
  REQUIRE(stream.Add(2000 * kMs, YawPose(1, 2, 3, M_PI / 2)) == PoseStream::AddResult::kAdded);

  const PoseLookup r = stream.Lookup(1250 * kMs, 1000 * kMs);
  REQUIRE(r.ok());
  CHECK(r.before_ns == 1000 * kMs);
  CHECK(r.after_ns == 2000 * kMs);
  const Vector7d v = r.pose->ToVector7();
  // Translation: a quarter of the way; rotation: a quarter of 90 deg about z (SLERP).
  CHECK(v(0) == Approx(0.25).margin(1e-12));
  CHECK(v(1) == Approx(0.5).margin(1e-12));
  CHECK(v(2) == Approx(0.75).margin(1e-12));
  CHECK(v(3) == Approx(0.0).margin(1e-12));
  CHECK(v(4) == Approx(0.0).margin(1e-12));
  CHECK(v(5) == Approx(std::sin(M_PI / 16)).margin(1e-12));
  CHECK(v(6) == Approx(std::cos(M_PI / 16)).margin(1e-12));

  // An exact stamp gives that pose, whatever the tolerance.
  const PoseLookup exact = stream.Lookup(2000 * kMs, 0);
  REQUIRE(exact.ok());
  CHECK(exact.pose->equals(YawPose(1, 2, 3, M_PI / 2), 1e-12));
}

TEST_CASE("PoseStream says why there is no pose", "[unit]") {
  PoseStream stream(16);
  CHECK(stream.Lookup(5 * kMs, kMs).status == PoseLookupStatus::kEmpty);
  stream.Add(100 * kMs, YawPose(0, 0, 0, 0));
  stream.Add(200 * kMs, YawPose(1, 0, 0, 0));
  const PoseLookup old = stream.Lookup(99 * kMs, 1000 * kMs);
  CHECK(old.status == PoseLookupStatus::kTooOld);
  CHECK_FALSE(old.pose.has_value());
  CHECK(old.Describe(99 * kMs).find("older than the oldest") != std::string::npos);
  const PoseLookup later = stream.Lookup(201 * kMs, 1000 * kMs);
  CHECK(later.status == PoseLookupStatus::kNotYet);
  CHECK(later.Describe(201 * kMs).find("newer than the newest") != std::string::npos);
  const PoseLookup gap = stream.Lookup(150 * kMs, 49 * kMs);
  CHECK(gap.status == PoseLookupStatus::kGapTooBig);
  CHECK(std::string(ToString(gap.status)) == "gap_too_big");
}

TEST_CASE("PoseStream tolerance edges: both bracketing poses must be within it", "[unit]") {
  PoseStream stream(16);
  stream.Add(0, YawPose(0, 0, 0, 0));
  stream.Add(100 * kMs, YawPose(1, 0, 0, 0));
  // Midway: 50 ms to each side.
  CHECK(stream.Lookup(50 * kMs, 50 * kMs).ok());
  CHECK(stream.Lookup(50 * kMs, 50 * kMs - 1).status == PoseLookupStatus::kGapTooBig);
  // Near the first: 10 ms before, 90 ms after; the farther one decides.
  const PoseLookup near = stream.Lookup(10 * kMs, 90 * kMs);
  REQUIRE(near.ok());
  CHECK(near.pose->translation().x() == Approx(0.1).margin(1e-12));
  CHECK(stream.Lookup(10 * kMs, 90 * kMs - 1).status == PoseLookupStatus::kGapTooBig);
}

TEST_CASE("PoseStream keeps poses sorted whatever the arrival order, duplicates replace",
          "[unit]") {
  PoseStream stream(16);
  stream.Add(300 * kMs, YawPose(3, 0, 0, 0));
  stream.Add(100 * kMs, YawPose(1, 0, 0, 0));
  stream.Add(200 * kMs, YawPose(2, 0, 0, 0));
  CHECK(stream.oldest_ns() == 100 * kMs);
  CHECK(stream.newest_ns() == 300 * kMs);
  PoseLookup r = stream.Lookup(150 * kMs, 60 * kMs);  // between 100 and 200, not 100 and 300
  REQUIRE(r.ok());
  CHECK(r.before_ns == 100 * kMs);
  CHECK(r.after_ns == 200 * kMs);
  CHECK(r.pose->translation().x() == Approx(1.5).margin(1e-12));

  CHECK(stream.Add(200 * kMs, YawPose(4, 0, 0, 0)) == PoseStream::AddResult::kDuplicate);
  CHECK(stream.size() == 3);
  r = stream.Lookup(150 * kMs, 60 * kMs);
  REQUIRE(r.ok());
  CHECK(r.pose->translation().x() == Approx(2.5).margin(1e-12));
}

TEST_CASE("PoseStream is bounded: the oldest poses go first", "[unit]") {
  PoseStream stream(3);
  for (int i = 1; i <= 4; ++i) stream.Add(i * 100 * kMs, YawPose(i, 0, 0, 0));
  CHECK(stream.size() == 3);
  CHECK(stream.oldest_ns() == 200 * kMs);
  CHECK(stream.Lookup(150 * kMs, kMs * 1000).status == PoseLookupStatus::kTooOld);
  // Full: a pose older than everything kept would be evicted at once, so it is refused.
  CHECK(stream.Add(50 * kMs, YawPose(0, 0, 0, 0)) == PoseStream::AddResult::kTooOld);
  CHECK(stream.oldest_ns() == 200 * kMs);
  // A late pose inside the range still goes in (and pushes out the oldest).
  CHECK(stream.Add(350 * kMs, YawPose(3.5, 0, 0, 0)) == PoseStream::AddResult::kAdded);
  CHECK(stream.oldest_ns() == 300 * kMs);
  CHECK_THROWS_AS(PoseStream(1), std::invalid_argument);
}

}  // namespace
}  // namespace p2i::scene
