/// @file coverage_test.cc
/// @brief Coverage score: 1 at training poses, monotonically decreasing away from them.
#include <cmath>

#include <catch2/catch.hpp>

#include "model/coverage.h"

using namespace p2i::model;
using p2i::scene::Pose;

namespace {

Pose At(double x, double y, double yaw_deg) {
  return Pose(Eigen::Vector3d(x, y, 0.0),
              Eigen::Quaterniond(Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY())));
}

/// 11 poses on a line x = 0 .. 1, step 0.1 m.
std::vector<Pose> Line() {
  std::vector<Pose> poses;
  for (int i = 0; i <= 10; ++i) poses.push_back(At(0.1 * i, 0.0, 0.0));
  return poses;
}

}  // namespace

TEST_CASE("CombinedPoseDistance and NearestPoseIndices", "[unit]") {
  CHECK(CombinedPoseDistance(At(0, 0, 0), At(0.3, 0.4, 20), 0.01) == Approx(0.5 + 0.2));
  const auto poses = Line();
  const auto idx = NearestPoseIndices(poses, At(0.52, 0.0, 0.0), 3, 0.01);
  REQUIRE(idx.size() == 3);
  CHECK(idx[0] == 5);
  CHECK(idx[1] == 6);
  CHECK(idx[2] == 4);
  CHECK(NearestPoseIndices(poses, At(0, 0, 0), 50, 0.01).size() == poses.size());
}

TEST_CASE("Coverage score is 1 at training poses and decreases away from them", "[unit]") {
  const CoverageScorer scorer(Line());
  CHECK(scorer.spacing() == Approx(0.1));
  for (const auto& p : Line()) CHECK(scorer.Score(p) == Approx(1.0).margin(1e-12));
  // Between two training poses (on the trajectory but not at a sample) the score stays high.
  CHECK(scorer.Score(At(0.55, 0.0, 0.0)) > 0.9);
  // Sideways translation swept outward: strictly decreasing.
  double prev = 1.0;
  for (double y : {0.02, 0.05, 0.1, 0.2, 0.4, 0.8}) {
    const double s = scorer.Score(At(0.5, y, 0.0));
    CHECK(s < prev);
    CHECK(s > 0.0);
    prev = s;
  }
  CHECK(prev < 0.01);  // far away: near 0
  // The documented formula at one spacing sideways.
  CHECK(scorer.Score(At(0.5, 0.1, 0.0)) == Approx(std::exp(-0.25)));
  // Rotation swept outward: strictly decreasing too.
  prev = 1.0;
  for (double yaw : {2.0, 5.0, 10.0, 30.0, 90.0}) {
    const double s = scorer.Score(At(0.5, 0.0, yaw));
    CHECK(s < prev);
    prev = s;
  }
}

TEST_CASE("Coverage score options and degenerate training sets", "[unit]") {
  CoverageOptions o;
  o.fallback_spacing_m = 0.2;
  const CoverageScorer single({At(0, 0, 0)}, o);
  CHECK(single.spacing() == Approx(0.2));
  CHECK(single.Score(At(0, 0, 0)) == Approx(1.0));
  CHECK(single.Score(At(0.4, 0, 0)) == Approx(std::exp(-1.0)));
  CHECK_THROWS_AS(CoverageScorer({}), std::invalid_argument);
  o.falloff = 0.0;
  CHECK_THROWS_AS(CoverageScorer({At(0, 0, 0)}, o), std::invalid_argument);
}
