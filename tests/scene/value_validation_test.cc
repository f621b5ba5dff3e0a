/// @file value_validation_test.cc
/// @brief Values files used to accept: a TUM quaternion of norm 1.8 (the wire's 1e-3
/// tolerance applies to files too), a NaN in a poses file (reported as a NaN at its line), a
/// 7-Scenes pose with a zero or scaled rotation block, a capture manifest whose frame_count
/// disagrees with its list.
#include <filesystem>
#include <fstream>
#include <iterator>

#include <catch2/catch.hpp>

#include "scene/capture.h"
#include "scene/pose.h"
#include "scene/trajectory_io.h"
#include "tests/read_file.h"
#include "tests/scene/dataset_test_util.h"

namespace p2i::scene {
namespace {
using p2i::testing::MakeSample;
using p2i::testing::TempDir;

CameraInfo SmallCamera() { return CameraInfo::Pinhole(40, 30, 40.0, 40.0, 19.5, 14.5); }
}  // namespace

TEST_CASE("TUM lines: quaternion norm within 1e-3, NaN named at its line", "[unit]") {
  CHECK_THROWS_WITH(ParseTumTrajectory("# c\n1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1.8\n", "t.txt",
                                       TumStampOrder::kStrict),
                    Catch::Contains("t.txt:3") && Catch::Contains("norm 1.8"));
  CHECK_THROWS_WITH(ParseTumTrajectory("1 0 0 0 0 0 0 1\n2 0 nan 0 0 0 0 1\n", "t.txt",
                                       TumStampOrder::kStrict),
                    Catch::Contains("t.txt:2") && Catch::Contains("ty is NaN"));
  CHECK_THROWS_WITH(ParseTumTrajectory("1 0 0 0 0 0 0 x\n", "t.txt", TumStampOrder::kStrict),
                    Catch::Contains("qw 'x' is not a number"));
  // Within the tolerance (4-decimal files) it is accepted and normalised.
  const auto ok = ParseTumTrajectory("1 0 0 0 0 0 0.7071 0.7071\n", "t.txt", TumStampOrder::kStrict);
  REQUIRE(ok.size() == 1);
}

TEST_CASE("A rotation block that is not a rotation is refused", "[unit]") {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<3, 3>(0, 0).setZero();
  CHECK_THROWS_WITH(Pose::FromMatrix(m), Catch::Contains("not a rotation"));
  m = Eigen::Matrix4d::Identity();
  m.block<3, 3>(0, 0) *= 2.0;
  CHECK_THROWS_WITH(Pose::FromMatrix(m), Catch::Contains("not a rotation"));
  m = Eigen::Matrix4d::Identity();
  m(0, 1) = 1e-4;  // slightly off, as datasets store them: accepted
  CHECK_NOTHROW(Pose::FromMatrix(m));
}

TEST_CASE("A capture manifest whose frame_count disagrees with its list is refused", "[unit]") {
  TempDir tmp;
  const std::string dir = tmp / "cap";
  {
    CaptureWriter writer(dir, SmallCamera());
    writer.Append(MakeSample(40, 30, 0, 1.0, Pose()));
    writer.Append(MakeSample(40, 30, 1, 2.0, Pose()));
  }
  std::string text = p2i::testing::ReadFile(dir + "/manifest.yaml");
  text.replace(text.find("frame_count: 2"), 14, "frame_count: 3");
  std::ofstream(dir + "/manifest.yaml") << text;
  CHECK_THROWS_WITH(ReadCapture(dir), Catch::Contains("frame_count is 3") &&
                                          Catch::Contains("lists 2"));
}

}  // namespace p2i::scene
