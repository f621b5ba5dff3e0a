/// @file capture_test.cc
/// @brief p2i capture folder: round trip, manifest checks, and a writer killed mid-write.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include <catch2/catch.hpp>

#include "scene/capture.h"
#include "scene/dataset_loader.h"
#include "tests/read_file.h"
#include "tests/scene/dataset_test_util.h"

namespace p2i::scene {
namespace {

using p2i::testing::MakePose;
using p2i::testing::MakeSample;
using p2i::testing::TempDir;

CameraInfo SmallCamera(int w = 40, int h = 30) {
  return CameraInfo::Pinhole(w, h, 50.0, 50.0, w / 2.0, h / 2.0, "test");
}

TEST_CASE("Capture round trip keeps pixels, depth in mm, poses and stamps", "[unit]") {
  TempDir tmp;
  const std::string dir = tmp / "cap";
  std::vector<RgbdSample> written;
  {
    CaptureWriter writer(dir, SmallCamera());
    for (int i = 0; i < 4; ++i) {
      written.push_back(MakeSample(40, 30, i, 0.05 * i + 1000.0, MakePose(0.1 * i, 5.0 * i)));
      writer.Append(written.back());
    }
    CHECK(writer.size() == 4);
  }
  const DatasetIndex index = ReadCapture(dir);
  REQUIRE(index.size() == 4);
  CHECK(index.camera().equals(SmallCamera(), 1e-9));
  CHECK(index.Sequences() == std::vector<std::string>{"cap"});
  for (size_t i = 0; i < 4; ++i) {
    const RgbdSample s = index.Load(i);
    CHECK(s.id == "cap/" + std::string(i < 10 ? "00000" : "0000") + std::to_string(i));
    CHECK(s.stamp == Approx(written[i].stamp).margin(1e-9));
    CHECK(s.pose.equals(written[i].pose, 1e-9));
    CHECK(cv::norm(s.rgb, written[i].rgb, cv::NORM_INF) == 0.0);
    // Depth is stored in whole millimetres; MakeSample uses whole millimetres too.
    CHECK(cv::norm(s.depth, written[i].depth, cv::NORM_INF) < 1e-6);
    CHECK(cv::countNonZero(s.depth == 0.0f) == cv::countNonZero(written[i].depth == 0.0f));
  }
  // OpenDataset detects the layout, both for the folder and for its parent.
  CHECK(DetectDatasetFormat(dir) == "capture");
  CHECK(OpenDataset(dir).size() == 4);
  CHECK(OpenDataset(tmp.path()).size() == 4);
}

TEST_CASE("Capture writer rejects wrong sizes and an existing capture", "[unit]") {
  TempDir tmp;
  const std::string dir = tmp / "cap";
  CaptureWriter writer(dir, SmallCamera());
  CHECK_THROWS_AS(writer.Append(MakeSample(41, 30, 0, 0.0, Pose())), std::invalid_argument);
  CHECK(writer.size() == 0);
  CHECK_THROWS_WITH(CaptureWriter(dir, SmallCamera()), Catch::Contains("already holds"));
  CaptureWriter::Options o;
  o.overwrite = true;
  CHECK_NOTHROW(CaptureWriter(dir, SmallCamera(), o));
}

TEST_CASE("Capture reader names the problem in a broken folder", "[unit]") {
  TempDir tmp;
  const std::string dir = tmp / "cap";
  {
    CaptureWriter writer(dir, SmallCamera());
    writer.Append(MakeSample(40, 30, 0, 1.0, Pose()));
    writer.Append(MakeSample(40, 30, 1, 2.0, Pose()));
  }
  SECTION("missing image") {
    std::filesystem::remove(dir + "/depth/000001.png");
    CHECK_THROWS_WITH(ReadCapture(dir), Catch::Contains("depth/000001.png"));
  }
  SECTION("unknown manifest key") {
    std::ofstream(dir + "/manifest.yaml", std::ios::app) << "colour_space: srgb\n";
    CHECK_THROWS_WITH(ReadCapture(dir), Catch::Contains("colour_space"));
  }
  SECTION("future version") {
    std::string text = p2i::testing::ReadFile(dir + "/manifest.yaml");
    text.replace(text.find("version: 1"), 10, "version: 9");
    std::ofstream(dir + "/manifest.yaml") << text;
    CHECK_THROWS_WITH(ReadCapture(dir), Catch::Contains("version 9"));
  }
  SECTION("no manifest") {
    CHECK_THROWS_WITH(ReadCapture(tmp.path()), Catch::Contains("no manifest.yaml"));
  }
}

TEST_CASE("A capture writer killed with SIGKILL mid-write leaves a readable folder",
          "[integration]") {
  TempDir tmp;
  const std::string dir = tmp / "cap";
  const int kWidth = 320, kHeight = 240;  // big enough that a frame write takes a while
  for (int round = 0; round < 3; ++round) {
    std::filesystem::remove_all(dir);
    const pid_t child = fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      // The writer: append frames until killed. Only async-signal-safe exits from here.
      try {
        CaptureWriter writer(dir, SmallCamera(kWidth, kHeight));
        for (int i = 0;; ++i) {
          writer.Append(MakeSample(kWidth, kHeight, i % 50, 0.05 * i, MakePose(0.01 * i, i)));
        }
      } catch (...) {
        _exit(3);
      }
    }
    // Kill at a different moment each round once a few frames are listed.
    const size_t wait_frames = 3 + 4 * round;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    size_t listed = 0;
    while (std::chrono::steady_clock::now() < deadline) {
      try {
        if (std::filesystem::exists(dir + "/manifest.yaml")) listed = ReadCapture(dir).size();
      } catch (const std::exception&) {
        // The reader may race the writer's first files; that is what we test after the kill.
      }
      if (listed >= wait_frames) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(2 + round * 3));
    }
    kill(child, SIGKILL);
    int status = 0;
    waitpid(child, &status, 0);
    REQUIRE(WIFSIGNALED(status));
    REQUIRE(listed >= wait_frames);

    const DatasetIndex index = ReadCapture(dir);
    INFO("round " << round << ": " << index.size() << " frames listed after the kill");
    CHECK(index.size() >= listed);
    for (size_t i = 0; i < index.size(); ++i) {
      const RgbdSample s = index.Load(i);
      const RgbdSample expected =
          MakeSample(kWidth, kHeight, static_cast<int>(i % 50), 0.05 * i, MakePose(0.01 * i, i));
      CHECK(cv::norm(s.rgb, expected.rgb, cv::NORM_INF) == 0.0);
      CHECK(s.pose.equals(expected.pose, 1e-9));
    }
  }
}

}  // namespace
}  // namespace p2i::scene
