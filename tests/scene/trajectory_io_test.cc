#include "scene/trajectory_io.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>

#include "scene/trajectory.h"

using p2i::scene::ParseTumTrajectory;
using p2i::scene::Pose;
using p2i::scene::StampedPose;

TEST_CASE("TUM trajectories round-trip through a file", "[unit]") {
  p2i::scene::OrbitOptions o;
  o.revolutions = 0.25;
  const auto t = p2i::scene::GenerateOrbit(o);
  const std::string path = "/tmp/p2i_trajectory_io_test_" + std::to_string(::getpid()) + ".txt";
  p2i::scene::WriteTumTrajectory(path, t, "orbit\nsecond comment line");
  const auto back = p2i::scene::ReadTumTrajectory(path);
  std::remove(path.c_str());
  REQUIRE(back.size() == t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    CHECK(back[i].stamp == Approx(t[i].stamp).margin(1e-9));
    CHECK(back[i].pose.equals(t[i].pose, 1e-8));
  }
  CHECK(p2i::scene::FormatTumTrajectory(t, "orbit").rfind("# orbit\n", 0) == 0);
}

TEST_CASE("TUM trajectory parsing skips comments and blank lines, errors name the line", "[unit]") {
  const std::string text =
      "# ground truth\n"
      "\n"
      "1.0 0 0 1 0 0 0 1\n"
      "   # indented comment\r\n"
      "1.05 0.1 0 1 0 0 0.7071068 0.7071068\r\n";
  const auto t = ParseTumTrajectory(text, "gt.txt");
  REQUIRE(t.size() == 2);
  CHECK(t[1].stamp == Approx(1.05));
  CHECK(t[1].pose.translation().x() == Approx(0.1));
  CHECK(Pose::RotationDistanceDeg(t[0].pose, t[1].pose) == Approx(90.0).margin(1e-4));

  CHECK_THROWS_WITH(ParseTumTrajectory("# c\n1.0 0 0 1 0 0 0 1\n2.0 0 0 1 0 0\n", "gt.txt"),
                    Catch::Contains("gt.txt:3"));
  CHECK_THROWS_WITH(ParseTumTrajectory("1.0 0 0 1 0 0 0 1\n1.0 0 0 1 0 0 0 1\n", "gt.txt"),
                    Catch::Contains("gt.txt:2") && Catch::Contains("sorted"));
  CHECK_THROWS_WITH(ParseTumTrajectory("1.0 0 0 x 0 0 0 1\n", "gt.txt"),
                    Catch::Contains("gt.txt:1"));
  CHECK_THROWS_WITH(p2i::scene::ReadTumTrajectory("/nonexistent/gt.txt"),
                    Catch::Contains("/nonexistent/gt.txt"));
  CHECK(ParseTumTrajectory("", "empty.txt").empty());
}

TEST_CASE("TUM trajectories recorded out of order are sorted on request", "[unit]") {
  using p2i::scene::TumStampOrder;
  const std::string text =
      "2.0 2 0 0 0 0 0 1\n"
      "1.0 1 0 0 0 0 0 1\n"
      "3.0 3 0 0 0 0 0 1\n";
  CHECK_THROWS_WITH(ParseTumTrajectory(text, "gt.txt"), Catch::Contains("gt.txt:2"));
  const auto t = ParseTumTrajectory(text, "gt.txt", TumStampOrder::kSort);
  REQUIRE(t.size() == 3);
  for (std::size_t i = 0; i < t.size(); ++i) {
    CHECK(t[i].stamp == Approx(1.0 + static_cast<double>(i)));
    CHECK(t[i].pose.translation().x() == Approx(1.0 + static_cast<double>(i)));
  }
}
