/// @file dataset_tum_rgbd_test.cc
/// @brief TUM RGB-D reader: association, interpolated poses, depth / 5000.
#include <filesystem>
#include <fstream>

#include <catch2/catch.hpp>
#include <opencv2/imgcodecs.hpp>

#include "scene/dataset_loader.h"
#include "scene/tum_rgbd.h"
#include "tests/scene/dataset_test_util.h"

namespace p2i::scene {
namespace {

namespace fs = std::filesystem;
using p2i::testing::TempDir;

TEST_CASE("AssociateStamps pairs nearest stamps one-to-one within the window", "[unit]") {
  const std::vector<double> a = {1.00, 1.10, 1.20, 1.30};
  const std::vector<double> b = {1.005, 1.09, 1.25, 1.301, 1.302};
  const auto pairs = AssociateStamps(a, b, 0.02);
  // 1.20 has nothing within 0.02; 1.30 takes 1.301 (closest), not 1.302.
  REQUIRE(pairs.size() == 3);
  CHECK(pairs[0] == std::make_pair<size_t, size_t>(0, 0));
  CHECK(pairs[1] == std::make_pair<size_t, size_t>(1, 1));
  CHECK(pairs[2] == std::make_pair<size_t, size_t>(3, 3));
  // Greedy by difference: b = 1.0 is nearer to a = 1.004 than to a = 0.99.
  const auto greedy = AssociateStamps({0.99, 1.004}, {1.0}, 0.02);
  REQUIRE(greedy.size() == 1);
  CHECK(greedy[0].first == 1);
}

TEST_CASE("TUM RGB-D reader: frames, depth scale, interpolated poses", "[unit]") {
  TempDir tmp;
  fs::create_directories(tmp / "rgb");
  fs::create_directories(tmp / "depth");
  std::ofstream rgb_txt(tmp / "rgb.txt"), depth_txt(tmp / "depth.txt"), gt(tmp / "groundtruth.txt");
  rgb_txt << "# color images\n# file: 'x.bag'\n# timestamp filename\n";
  depth_txt << "# depth maps\n# \n# timestamp filename\n";
  gt << "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n";
  // Ground truth at 0.0 and 1.0: x goes 0 -> 1, yaw 0 -> 90 deg.
  const Pose p0(Eigen::Vector3d(0, 0, 0), Eigen::Quaterniond::Identity());
  const Pose p1(Eigen::Vector3d(1, 0, 0),
                Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())));
  gt << p0.ToTumLine(100.0) << "\n" << p1.ToTumLine(101.0) << "\n";
  const double stamps[] = {100.25, 100.5, 100.75, 102.0};  // the last one is past the truth
  for (int i = 0; i < 4; ++i) {
    const std::string name = std::to_string(i) + ".png";
    cv::Mat bgr(8, 10, CV_8UC3, cv::Scalar(10 * i, 20, 30));  // B = 10 i, R = 30
    cv::imwrite(tmp / ("rgb/" + name), bgr);
    cv::Mat d(8, 10, CV_16UC1, cv::Scalar(5000 * (i + 1)));
    d.at<uint16_t>(0, 0) = 0;
    cv::imwrite(tmp / ("depth/" + name), d);
    char line[128];
    std::snprintf(line, sizeof(line), "%.6f rgb/%s\n", stamps[i], name.c_str());
    rgb_txt << line;
    std::snprintf(line, sizeof(line), "%.6f depth/%s\n", stamps[i] + 0.01, name.c_str());
    depth_txt << line;
  }
  rgb_txt.close();
  depth_txt.close();
  gt.close();

  // The ground truth here is 1 s apart (TUM's is 100 Hz): allow the gap.
  TumRgbdOptions options;
  options.max_pose_gap = 1.5;
  int dropped = -1;
  const DatasetIndex index = ReadTumRgbd(tmp.path(), options, &dropped);
  REQUIRE(index.size() == 3);
  CHECK(dropped == 1);
  CHECK(index.camera().fx() == Approx(525.0 * 10 / 640.0));
  CHECK(index.frames()[1].stamp == Approx(100.5));
  const Pose mid = index.frames()[1].pose;
  CHECK(mid.translation().x() == Approx(0.5));
  CHECK(Pose::RotationDistanceDeg(mid, p0) == Approx(45.0).margin(1e-6));
  const RgbdSample s = index.Load(2);
  CHECK(s.rgb.at<cv::Vec3b>(0, 0) == cv::Vec3b(30, 20, 20));  // RGB order
  CHECK(s.depth.at<float>(1, 1) == Approx(3.0f));             // 15000 / 5000
  CHECK(s.depth.at<float>(0, 0) == 0.0f);

  SECTION("a tight association window drops every frame: clear error") {
    TumRgbdOptions o = options;
    o.max_difference = 0.001;
    CHECK_THROWS_WITH(ReadTumRgbd(tmp.path(), o), Catch::Contains("no rgb image has a depth"));
  }
  SECTION("the default pose gap (0.1 s) drops frames between 1 s apart poses") {
    CHECK_THROWS(ReadTumRgbd(tmp.path()));
  }
  SECTION("OpenDataset detects it") {
    CHECK(DetectDatasetFormat(tmp.path()) == "tum");
    DatasetOptions o;
    o.tum_max_pose_gap = 1.5;
    CHECK(OpenDataset(tmp.path(), o).size() == 3);
  }
  SECTION("malformed ground truth names file and line") {
    std::ofstream(tmp / "groundtruth.txt", std::ios::app) << "103.0 1 2 3\n";
    CHECK_THROWS_WITH(ReadTumRgbd(tmp.path(), options),
                      Catch::Contains("groundtruth.txt:5"));
  }
}

}  // namespace
}  // namespace p2i::scene
