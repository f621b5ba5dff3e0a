#include "scene/trajectory.h"

#include <yaml-cpp/yaml.h>

#include <catch2/catch.hpp>
#include <cmath>

#include "scene/sim_scene.h"

using p2i::scene::AdjacentSweepsOptions;
using p2i::scene::ArmSweepOptions;
using p2i::scene::LookAt;
using p2i::scene::OrbitOptions;
using p2i::scene::Pose;
using p2i::scene::RandomWalkOptions;
using p2i::scene::SimScene;
using p2i::scene::StampedPose;

namespace {

// Every pose free (inside the room, `clearance` from objects), stamps at `rate_hz`, and
// consecutive poses within `max_step` metres and `max_turn_deg` degrees.
void CheckTrajectory(const std::vector<StampedPose>& t, const SimScene& scene, double rate_hz,
                     double max_step, double max_turn_deg, double clearance = 0.1) {
  REQUIRE(t.size() > 10);
  int not_free = 0, bad_stamp = 0, big_step = 0, big_turn = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!scene.IsFree(t[i].pose.translation(), clearance)) ++not_free;
    if (i == 0) continue;
    if (std::abs(t[i].stamp - t[i - 1].stamp - 1.0 / rate_hz) > 1e-9) ++bad_stamp;
    if (Pose::TranslationDistance(t[i].pose, t[i - 1].pose) > max_step) ++big_step;
    if (Pose::RotationDistanceDeg(t[i].pose, t[i - 1].pose) > max_turn_deg) ++big_turn;
  }
  CHECK(not_free == 0);
  CHECK(bad_stamp == 0);
  CHECK(big_step == 0);
  CHECK(big_turn == 0);
}

}  // namespace

TEST_CASE("LookAt builds an OpenCV camera looking at the target, z up", "[unit]") {
  const Pose p = LookAt({1.0, 2.0, 1.5}, {4.0, 2.0, 1.5});
  CHECK((p.Forward() - Eigen::Vector3d::UnitX()).norm() < 1e-12);
  // Camera x is right (world -y when looking along +x), camera y is down (world -z).
  CHECK((p.rotation() * Eigen::Vector3d::UnitX() - Eigen::Vector3d(0, -1, 0)).norm() < 1e-12);
  CHECK((p.rotation() * Eigen::Vector3d::UnitY() - Eigen::Vector3d(0, 0, -1)).norm() < 1e-12);
  CHECK_THROWS_AS(LookAt({0, 0, 0}, {0, 0, 1}), std::invalid_argument);
  CHECK_THROWS_AS(LookAt({0, 0, 0}, {0, 0, 0}), std::invalid_argument);
}

TEST_CASE("Arm sweep: arcs at each height, free and smooth in both offices", "[unit]") {
  ArmSweepOptions o;
  const auto t = p2i::scene::GenerateArmSweep(o);
  const double step = o.speed / o.rate_hz;
  for (const auto& name : SimScene::BuiltInNames()) {
    CheckTrajectory(t, SimScene::BuiltIn(name), 20.0, step + 1e-6, 2.0);
  }
  // Every pose is `reach` from the base axis at one of the heights or between them, and looks
  // away from the base (into the room).
  int at_height = 0;
  for (const auto& sp : t) {
    const Eigen::Vector3d p = sp.pose.translation();
    CHECK(std::hypot(p.x() - o.base.x(), p.y() - o.base.y()) == Approx(o.reach).margin(1e-9));
    const Eigen::Vector2d radial(p.x() - o.base.x(), p.y() - o.base.y());
    CHECK(sp.pose.Forward().head<2>().dot(radial) > 0.0);
    for (double h : o.heights) {
      if (std::abs(p.z() - h) < 1e-9) ++at_height;
    }
  }
  CHECK(at_height > static_cast<int>(t.size()) * 3 / 4);
  CHECK(t.front().pose.translation().z() == Approx(o.heights.front()));
  CHECK(t.back().pose.translation().z() == Approx(o.heights.back()));
  // Length: three arcs of 120 degrees at 0.5 m and two 0.3 m climbs at 0.15 m/s, 20 Hz.
  const double length = 3 * 0.5 * 2 * M_PI / 3 + 0.6;
  CHECK(t.size() == static_cast<std::size_t>(std::floor(length / step + 1e-9)) + 1);
}

TEST_CASE("Adjacent sweeps are offset by the configured distance", "[unit]") {
  AdjacentSweepsOptions o;
  o.count = 3;
  o.offset = 0.12;
  const auto radial = p2i::scene::GenerateAdjacentSweeps(o);
  REQUIRE(radial.size() == 3);
  const SimScene scene = SimScene::BuiltIn("small_office");
  for (std::size_t k = 0; k < radial.size(); ++k) {
    CheckTrajectory(radial[k], scene, 20.0, o.sweep.speed / o.sweep.rate_hz + 1e-6, 2.0);
    const Eigen::Vector3d p = radial[k].front().pose.translation();
    CHECK(std::hypot(p.x() - o.sweep.base.x(), p.y() - o.sweep.base.y()) ==
          Approx(o.sweep.reach + k * o.offset));
  }
  o.axis = AdjacentSweepsOptions::Axis::kVertical;
  const auto vertical = p2i::scene::GenerateAdjacentSweeps(o);
  REQUIRE(vertical.size() == 3);
  CHECK(vertical[0].size() == vertical[2].size());
  for (std::size_t i = 0; i < vertical[0].size(); i += 25) {
    const Eigen::Vector3d d = vertical[2][i].pose.translation() - vertical[0][i].pose.translation();
    CHECK((d - Eigen::Vector3d(0, 0, 2 * o.offset)).norm() < 1e-9);
  }
}

TEST_CASE("Orbit circles the point and looks at it", "[unit]") {
  OrbitOptions o;
  const auto t = p2i::scene::GenerateOrbit(o);
  CheckTrajectory(t, SimScene::BuiltIn("small_office"), o.rate_hz, o.speed / o.rate_hz + 1e-6, 2.0);
  CheckTrajectory(t, SimScene::BuiltIn("large_office"), o.rate_hz, o.speed / o.rate_hz + 1e-6, 2.0);
  for (const auto& sp : t) {
    const Eigen::Vector3d p = sp.pose.translation();
    CHECK(std::hypot(p.x() - o.center.x(), p.y() - o.center.y()) == Approx(o.radius));
    CHECK((sp.pose.Forward() - (o.center - p).normalized()).norm() < 1e-9);
  }
  CHECK(Pose::TranslationDistance(t.front().pose, t.back().pose) < o.speed / o.rate_hz + 1e-6);
}

TEST_CASE("Random walk stays in the room, off the furniture, moves smoothly, is seeded", "[unit]") {
  RandomWalkOptions o;
  o.duration = 60.0;
  o.seed = 3;
  for (const auto& name : SimScene::BuiltInNames()) {
    const SimScene scene = SimScene::BuiltIn(name);
    const auto t = p2i::scene::GenerateRandomWalk(o, scene);
    CHECK(t.size() == 1201);
    const double max_turn = std::hypot(o.max_turn_rate_deg, o.max_turn_rate_deg) / o.rate_hz;
    CheckTrajectory(t, scene, o.rate_hz, o.speed / o.rate_hz + 1e-9, max_turn + 1e-6, o.clearance);
    // It explores (not stuck at the start) and keeps looking into the room: the optical axis
    // hits something at least 0.4 m away in nearly every view.
    double travelled = 0.0;
    for (std::size_t i = 1; i < t.size(); ++i) {
      travelled += Pose::TranslationDistance(t[i].pose, t[i - 1].pose);
    }
    CHECK(travelled > 0.5 * o.speed * o.duration);
    int looking_at_wall = 0;
    const auto probe = p2i::scene::CameraInfo::Pinhole(3, 3, 2, 2, 1, 1);
    for (std::size_t i = 0; i < t.size(); i += 10) {
      const float z = scene.Render(t[i].pose, probe).depth.at<float>(1, 1);
      if (z < 0.4f) ++looking_at_wall;
    }
    CHECK(looking_at_wall <= 2);
    // Seeded.
    const auto again = p2i::scene::GenerateRandomWalk(o, scene);
    CHECK(again.back().pose.equals(t.back().pose, 0.0));
    RandomWalkOptions other = o;
    other.seed = 4;
    CHECK_FALSE(
        p2i::scene::GenerateRandomWalk(other, scene).back().pose.equals(t.back().pose, 1e-3));
  }
}

TEST_CASE("Trajectory options parse strictly from YAML", "[unit]") {
  const YAML::Node arm = YAML::Load("{reach: 0.7, heights: [1.1, 1.4], rate_hz: 10}");
  const ArmSweepOptions a = ArmSweepOptions::FromYaml(arm, "traj.yaml");
  CHECK(a.reach == 0.7);
  CHECK(a.heights == std::vector<double>{1.1, 1.4});
  CHECK(a.rate_hz == 10.0);
  CHECK(a.speed == ArmSweepOptions().speed);  // untouched default
  CHECK_THROWS_WITH(ArmSweepOptions::FromYaml(YAML::Load("reach: 0.6\nreech: 0.7\n"), "traj.yaml"),
                    Catch::Contains("traj.yaml:2") && Catch::Contains("reech"));
  CHECK_THROWS_WITH(ArmSweepOptions::FromYaml(YAML::Load("{rate_hz: -1}"), "traj.yaml"),
                    Catch::Contains("rate_hz"));
  const auto adj = AdjacentSweepsOptions::FromYaml(
      YAML::Load("{count: 4, offset: 0.05, axis: vertical, sweep: {arc_deg: 90}}"), "t.yaml");
  CHECK(adj.count == 4);
  CHECK(adj.axis == AdjacentSweepsOptions::Axis::kVertical);
  CHECK(adj.sweep.arc_deg == 90.0);
  CHECK_THROWS_WITH(AdjacentSweepsOptions::FromYaml(YAML::Load("{axis: diagonal}"), "t.yaml"),
                    Catch::Contains("radial or vertical"));
  CHECK_THROWS(OrbitOptions::FromYaml(YAML::Load("{radius: 0}"), "t.yaml"));
  CHECK_THROWS_WITH(
      RandomWalkOptions::FromYaml(YAML::Load("{min_height: 2, max_height: 1}"), "t.yaml"),
      Catch::Contains("min_height"));

  const SimScene scene = SimScene::BuiltIn("small_office");
  const auto sets = p2i::scene::GenerateTrajectoriesFromYaml(
      YAML::Load("{type: adjacent_sweeps, count: 2}"), "t.yaml", &scene);
  CHECK(sets.size() == 2);
  const auto walk = p2i::scene::GenerateTrajectoriesFromYaml(
      YAML::Load("{type: random_walk, duration: 2, seed: 1}"), "t.yaml", &scene);
  REQUIRE(walk.size() == 1);
  CHECK(walk[0].size() == 41);
  CHECK_THROWS_WITH(p2i::scene::GenerateTrajectoriesFromYaml(
                        YAML::Load("type: orbit\nradius: 1\nradiuss: 2\n"), "t.yaml", &scene),
                    Catch::Contains("t.yaml:3") && Catch::Contains("radiuss"));
  CHECK_THROWS_WITH(
      p2i::scene::GenerateTrajectoriesFromYaml(YAML::Load("{type: spiral}"), "t.yaml", &scene),
      Catch::Contains("spiral"));
  CHECK_THROWS_AS(p2i::scene::GenerateTrajectoriesFromYaml(YAML::Load("{type: random_walk}"),
                                                           "t.yaml", nullptr),
                  std::invalid_argument);
}
