/// @file dataset_seven_scenes_test.cc
/// @brief 7-Scenes reader on a small synthetic folder written in the 7-Scenes layout.
#include <filesystem>
#include <fstream>

#include <catch2/catch.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "scene/dataset_loader.h"
#include "scene/seven_scenes.h"
#include "tests/scene/dataset_test_util.h"

namespace p2i::scene {
namespace {

namespace fs = std::filesystem;
using p2i::testing::MakePose;
using p2i::testing::MakeSample;
using p2i::testing::TempDir;

/// Writes frame `number` of `seq` as 7-Scenes does: BGR colour, depth mm with `invalid` for holes.
RgbdSample WriteFrame(const std::string& seq_dir, int number, uint16_t invalid) {
  const RgbdSample s = MakeSample(32, 24, number, 0.0, MakePose(0.01 * number, number));
  char stem[64];
  std::snprintf(stem, sizeof(stem), "%s/frame-%06d", seq_dir.c_str(), number);
  cv::Mat bgr;
  cv::cvtColor(s.rgb, bgr, cv::COLOR_RGB2BGR);
  cv::imwrite(std::string(stem) + ".color.png", bgr);
  cv::Mat mm(s.depth.size(), CV_16UC1);
  for (int r = 0; r < mm.rows; ++r) {
    for (int c = 0; c < mm.cols; ++c) {
      const float d = s.depth.at<float>(r, c);
      mm.at<uint16_t>(r, c) = d == 0.0f ? invalid : static_cast<uint16_t>(std::lround(d * 1000));
    }
  }
  cv::imwrite(std::string(stem) + ".depth.png", mm);
  std::ofstream pose(std::string(stem) + ".pose.txt");
  pose.precision(17);
  const Eigen::Matrix4d m = s.pose.ToMatrix();
  for (int r = 0; r < 4; ++r) {
    pose << m(r, 0) << "\t" << m(r, 1) << "\t" << m(r, 2) << "\t" << m(r, 3) << "\t\n";
  }
  return s;
}

TEST_CASE("7-Scenes reader: order, ids, stamps, RGB order, invalid depth 65535", "[unit]") {
  TempDir tmp;
  std::vector<RgbdSample> expected;
  for (const char* seq : {"seq-02", "seq-01"}) {
    fs::create_directories(tmp / seq);
    for (int n : {12, 10, 11}) expected.push_back(WriteFrame(tmp / seq, n, 65535));
  }
  const DatasetIndex index = ReadSevenScenes(tmp.path());
  REQUIRE(index.size() == 6);
  CHECK(index.Sequences() == std::vector<std::string>{"seq-01", "seq-02"});
  CHECK(index.frames()[0].id == "seq-01/frame-000010");
  CHECK(index.frames()[2].id == "seq-01/frame-000012");
  CHECK(index.frames()[3].sequence == "seq-02");
  CHECK(index.frames()[1].stamp == Approx(11.0 / 30.0));
  // Default calibration of 7-Scenes, for the image's size.
  CHECK(index.camera().image_width == 32);
  CHECK(index.camera().fx() == Approx(585.0));

  const RgbdSample s = index.Load(0);  // seq-01 frame 10 == MakeSample(.., 10, ..)
  const RgbdSample want = MakeSample(32, 24, 10, 0.0, MakePose(0.1, 10));
  CHECK(cv::norm(s.rgb, want.rgb, cv::NORM_INF) == 0.0);
  CHECK(cv::norm(s.depth, want.depth, cv::NORM_INF) < 1e-6);
  CHECK(cv::countNonZero(s.depth == 0.0f) > 0);
  CHECK(s.pose.equals(want.pose, 1e-9));

  SECTION("one sequence folder, and the sequences option") {
    CHECK(ReadSevenScenes(tmp / "seq-02").size() == 3);
    SevenScenesOptions o;
    o.sequences = {"seq-02"};
    CHECK(ReadSevenScenes(tmp.path(), o).frames().front().id == "seq-02/frame-000010");
  }
  SECTION("OpenDataset detects it") {
    CHECK(DetectDatasetFormat(tmp.path()) == "7scenes");
    CHECK(OpenDataset(tmp.path()).size() == 6);
  }
  SECTION("intrinsics file in the root is used") {
    std::ofstream(tmp / "camera-intrinsics.txt") << "100 0 16\n0 110 12\n0 0 1\n";
    const DatasetIndex with = ReadSevenScenes(tmp.path());
    CHECK(with.camera().fx() == Approx(100.0));
    CHECK(with.camera().fy() == Approx(110.0));
  }
}

TEST_CASE("7-Scenes reader: invalid depth value is a parameter", "[unit]") {
  TempDir tmp;
  fs::create_directories(tmp / "seq-01");
  WriteFrame(tmp / "seq-01", 0, 0);
  // A 65535 pixel in a 0-invalid dataset is a (far) measurement, not a hole.
  cv::Mat mm = cv::imread(tmp / "seq-01/frame-000000.depth.png", cv::IMREAD_UNCHANGED);
  mm.at<uint16_t>(0, 1) = 65535;
  cv::imwrite(tmp / "seq-01/frame-000000.depth.png", mm);
  SevenScenesOptions o;
  o.depth.invalid_value = 0;
  CHECK(ReadSevenScenes(tmp.path(), o).Load(0).depth.at<float>(0, 1) == Approx(65.535f));
  CHECK(ReadSevenScenes(tmp.path()).Load(0).depth.at<float>(0, 1) == 0.0f);
}

TEST_CASE("7-Scenes reader: errors name the file", "[unit]") {
  TempDir tmp;
  fs::create_directories(tmp / "seq-01");
  WriteFrame(tmp / "seq-01", 0, 65535);
  WriteFrame(tmp / "seq-01", 1, 65535);
  SECTION("missing depth") {
    fs::remove(tmp / "seq-01/frame-000001.depth.png");
    CHECK_THROWS_WITH(ReadSevenScenes(tmp.path()), Catch::Contains("frame-000001.depth.png"));
  }
  SECTION("malformed pose") {
    std::ofstream(tmp / "seq-01/frame-000001.pose.txt") << "1 0 0 0\n0 1 0 0\n0 0 x 0\n";
    CHECK_THROWS_WITH(ReadSevenScenes(tmp.path()),
                      Catch::Contains("frame-000001.pose.txt") && Catch::Contains("'x'"));
  }
  SECTION("depth that is not 16-bit") {
    cv::imwrite(tmp / "seq-01/frame-000001.depth.png", cv::Mat(24, 32, CV_8UC1, cv::Scalar(3)));
    const DatasetIndex index = ReadSevenScenes(tmp.path());
    CHECK_THROWS_WITH(index.Load(1), Catch::Contains("frame-000001.depth.png") &&
                                         Catch::Contains("16-bit"));
  }
  SECTION("no such folder") {
    CHECK_THROWS_WITH(ReadSevenScenes(tmp / "nope"), Catch::Contains("nope"));
  }
}

}  // namespace
}  // namespace p2i::scene
