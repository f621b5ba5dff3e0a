/// @file tum_sequence_writer_test.cc
/// @brief TumSequenceWriter: round trip, TUM text formats, ordering, crash safety under SIGKILL.
#include "nodes/slam_sink/tum_sequence_writer.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <thread>

#include <catch2/catch.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "scene/tum_rgbd.h"
#include "tests/read_file.h"
#include "tests/slam_sink/sink_test_util.h"

namespace p2i::slam_sink {
namespace {

namespace fs = std::filesystem;
using testing::DataLines;
using testing::Split;
using testing::TempDir;

SinkFrame PatternFrame(double stamp, uint64_t seq, bool synthetic, int width = 64,
                       int height = 48) {
  SinkFrame frame;
  frame.stamp = stamp;
  frame.seq = seq;
  frame.synthetic = synthetic;
  frame.source = synthetic ? "/synthesizer" : "/camera";
  frame.pose = scene::Pose(Eigen::Vector3d(0.1 * seq, -0.2, 1.0 + 0.01 * seq),
                           Eigen::Quaterniond(Eigen::AngleAxisd(0.05 * seq,
                                                                Eigen::Vector3d(0, 0, 1))));
  frame.rgb = cv::Mat(height, width, CV_8UC3);
  frame.depth = cv::Mat(height, width, CV_32FC1);
  cv::RNG rng(77 + seq);
  rng.fill(frame.rgb, cv::RNG::UNIFORM, 0, 256);
  rng.fill(frame.depth, cv::RNG::UNIFORM, 0.2, 12.0);
  frame.depth.at<float>(0, 0) = 0.0f;  // invalid stays invalid
  frame.coverage = 0.75;
  return frame;
}

TumSequenceWriterOptions OptionsFor(const TempDir& dir) {
  TumSequenceWriterOptions options;
  options.out_dir = dir.path();
  return options;
}

TEST_CASE("TumSequenceWriter round-trips colour exactly and depth within 1/5000 m",
          "[unit]") {
  TempDir dir("roundtrip");
  std::vector<SinkFrame> frames;
  {
    TumSequenceWriter writer(OptionsFor(dir));
    for (uint64_t i = 0; i < 3; ++i) {
      frames.push_back(PatternFrame(100.0 + 0.1 * i, i, true));
      const WrittenFiles files = writer.Write(frames.back());
      CHECK(fs::exists(dir / files.rgb));
      CHECK(fs::exists(dir / files.depth));
    }
    writer.Close();
    CHECK(writer.frames_written() == 3);
  }
  const auto rgb_lines = DataLines(dir / "rgb.txt");
  const auto depth_lines = DataLines(dir / "depth.txt");
  REQUIRE(rgb_lines.size() == 3);
  REQUIRE(depth_lines.size() == 3);
  for (size_t i = 0; i < frames.size(); ++i) {
    const auto rgb_tokens = Split(rgb_lines[i]);
    const auto depth_tokens = Split(depth_lines[i]);
    REQUIRE(rgb_tokens.size() == 2);
    REQUIRE(depth_tokens.size() == 2);
    CHECK(std::stod(rgb_tokens[0]) == Approx(frames[i].stamp).margin(1e-6));
    cv::Mat bgr = cv::imread((dir / rgb_tokens[1]), cv::IMREAD_UNCHANGED);
    REQUIRE(bgr.type() == CV_8UC3);
    cv::Mat rgb;
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
    CHECK(cv::norm(rgb, frames[i].rgb, cv::NORM_INF) == 0.0);

    cv::Mat units = cv::imread((dir / depth_tokens[1]), cv::IMREAD_UNCHANGED);
    REQUIRE(units.type() == CV_16UC1);
    const cv::Mat metres = TumSequenceWriter::DepthFromUnits(units, 5000.0);
    CHECK(metres.at<float>(0, 0) == 0.0f);
    double max_err = 0.0;
    for (int r = 0; r < metres.rows; ++r) {
      for (int c = 0; c < metres.cols; ++c) {
        const float expected = frames[i].depth.at<float>(r, c);
        if (expected <= 0.0f) continue;
        // 12 m * 5000 = 60000 units < 65535: everything is representable here.
        max_err = std::max(max_err, std::abs(double(metres.at<float>(r, c)) - expected));
      }
    }
    CHECK(max_err <= 0.5 / 5000.0 + 1e-6);
    CHECK(max_err > 0.0);  // really quantised, not a float copy
  }
}

TEST_CASE("TumSequenceWriter depth conversion invalidates what it cannot represent", "[unit]") {
  cv::Mat depth = (cv::Mat_<float>(1, 5) << 0.0f, -1.0f, NAN, 13.2f, 1.00001f);
  size_t out_of_range = 0;
  const cv::Mat units = TumSequenceWriter::DepthToUnits(depth, 5000.0, &out_of_range);
  CHECK(units.at<uint16_t>(0, 0) == 0);
  CHECK(units.at<uint16_t>(0, 1) == 0);
  CHECK(units.at<uint16_t>(0, 2) == 0);
  CHECK(units.at<uint16_t>(0, 3) == 0);  // 66000 units: beyond 16 bits
  CHECK(units.at<uint16_t>(0, 4) == 5000);
  CHECK(out_of_range == 1);
}

TEST_CASE("TumSequenceWriter text files follow the TUM formats and the reader accepts them",
          "[unit]") {
  TempDir dir("formats");
  {
    TumSequenceWriter writer(OptionsFor(dir));
    // Real and synthetic frames arrive out of time order; Close() interleaves them by time.
    writer.Write(PatternFrame(10.30, 3, true));
    writer.Write(PatternFrame(10.10, 1, true));
    writer.Write(PatternFrame(10.20, 7, false));
    SinkFrame no_pose = PatternFrame(10.25, 8, false);
    no_pose.has_pose = false;
    writer.Write(no_pose);
    FrameRecord record;
    record.check = "fail";
    record.translation_error_m = 0.1;
    record.rotation_error_deg = 2.0;
    writer.Write(PatternFrame(10.40, 4, true), record);
    writer.Close();
  }
  // Headers as TUM writes them.
  std::ifstream rgb_in(dir / "rgb.txt");
  std::string first;
  std::getline(rgb_in, first);
  CHECK(first == "# color images");
  std::ifstream depth_in(dir / "depth.txt");
  std::getline(depth_in, first);
  CHECK(first == "# depth maps");

  const auto rgb = DataLines(dir / "rgb.txt");
  REQUIRE(rgb.size() == 5);
  double last = -1.0;
  for (const auto& line : rgb) {
    const auto t = Split(line);
    REQUIRE(t.size() == 2);
    CHECK(std::stod(t[0]) > last);  // sorted by time after Close()
    last = std::stod(t[0]);
    CHECK(fs::exists(dir / t[1]));
  }
  // Groundtruth: 4 frames had a pose; each line parses as a TUM pose with the frame's pose.
  const auto gt = DataLines(dir / "groundtruth.txt");
  REQUIRE(gt.size() == 4);
  for (const auto& line : gt) {
    double stamp = 0.0;
    const scene::Pose pose = scene::Pose::FromTumLine(line, &stamp);
    const uint64_t seq = stamp < 10.15 ? 1 : stamp < 10.25 ? 7 : stamp < 10.35 ? 3 : 4;
    CHECK(pose.equals(PatternFrame(stamp, seq, true).pose, 1e-6));
  }
  // associations.txt: "t rgb t depth" with matching names.
  const auto assoc = DataLines(dir / "associations.txt");
  REQUIRE(assoc.size() == 5);
  for (const auto& line : assoc) {
    const auto t = Split(line);
    REQUIRE(t.size() == 4);
    CHECK(t[0] == t[2]);
    CHECK(t[1].substr(0, 4) == "rgb/");
    CHECK(t[3].substr(0, 6) == "depth/");
  }
  // frames.txt: the per-frame source flag and check result.
  const auto frames = DataLines(dir / "frames.txt");
  REQUIRE(frames.size() == 5);
  int synthetic = 0, real = 0, failed = 0;
  for (const auto& line : frames) {
    const auto t = Split(line);
    REQUIRE(t.size() == 9);
    synthetic += t[3] == "synthetic";
    real += t[3] == "real";
    failed += t[4] == "fail";
    if (t[4] == "fail") CHECK(std::stod(t[5]) == Approx(0.1));
  }
  CHECK(synthetic == 3);
  CHECK(real == 2);
  CHECK(failed == 1);

  // The project's own TUM reader (what the dataset loader uses) reads the folder.
  scene::TumRgbdOptions options;
  options.max_pose_gap = 0.2;  // the pose-less real frame at 10.25 is interpolated
  int dropped = -1;
  const scene::DatasetIndex index = scene::ReadTumRgbd(dir.path(), options, &dropped);
  CHECK(index.size() == 5);
  CHECK(dropped == 0);
}

TEST_CASE("TumSequenceWriter refuses to mix runs unless appending, and never reuses a name",
          "[unit]") {
  TempDir dir("append");
  {
    TumSequenceWriter writer(OptionsFor(dir));
    writer.Write(PatternFrame(5.0, 0, true));
  }
  CHECK_THROWS_WITH(TumSequenceWriter(OptionsFor(dir)), Catch::Contains("already exists"));
  TumSequenceWriterOptions options = OptionsFor(dir);
  options.append = true;
  {
    TumSequenceWriter writer(options);
    const WrittenFiles again = writer.Write(PatternFrame(5.0, 0, true));  // same stamp
    CHECK(again.rgb != "rgb/5.000000_syn.png");
  }
  const auto rgb = DataLines(dir / "rgb.txt");
  CHECK(rgb.size() == 2);
  const std::string text = p2i::testing::ReadFile(dir / "rgb.txt");
  size_t headers = 0;
  for (size_t p = text.find("# color images"); p != std::string::npos;
       p = text.find("# color images", p + 1)) {
    ++headers;
  }
  CHECK(headers == 1);
}

TEST_CASE("TumSequenceWriter rejects malformed frames without writing", "[unit]") {
  TempDir dir("bad");
  TumSequenceWriter writer(OptionsFor(dir));
  SinkFrame frame = PatternFrame(1.0, 0, true);
  frame.depth = cv::Mat(10, 10, CV_32FC1, cv::Scalar(1.0));
  CHECK_THROWS_AS(writer.Write(frame), std::invalid_argument);
  frame = PatternFrame(NAN, 0, true);
  CHECK_THROWS_AS(writer.Write(frame), std::invalid_argument);
  CHECK(writer.frames_written() == 0);
  CHECK(DataLines(dir / "rgb.txt").empty());
}

TEST_CASE("TumSequenceWriter killed with SIGKILL mid-run lists only complete files",
          "[integration]") {
  // Several runs killed at different instants, so some kills land inside a write.
  const int extra_delay_ms = GENERATE(0, 13, 37, 71);
  TempDir dir("sigkill");
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    // The child writes frames forever (larger images: more time inside each write).
    try {
      TumSequenceWriter writer(OptionsFor(dir));
      for (uint64_t i = 0;; ++i) writer.Write(PatternFrame(1000.0 + 0.01 * i, i, i % 3 != 0,
                                                           320, 240));
    } catch (...) {
    }
    ::_exit(3);
  }
  // Kill it at an arbitrary instant once it has written a few frames.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (DataLines(dir / "frames.txt").size() < 8 &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(extra_delay_ms));
  REQUIRE(::kill(child, SIGKILL) == 0);
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  REQUIRE(WIFSIGNALED(status));

  size_t checked = 0;
  for (const char* index : {"rgb.txt", "depth.txt", "associations.txt", "frames.txt"}) {
    const auto lines = DataLines(dir / index);
    CHECK(lines.size() >= 8);
    for (const auto& line : lines) {
      const auto t = Split(line);
      // A complete line: exactly the expected fields (no torn line at the end).
      const size_t fields = std::string(index) == "associations.txt" ? 4
                            : std::string(index) == "frames.txt"     ? 9
                                                                     : 2;
      REQUIRE(t.size() == fields);
      std::vector<std::string> files;
      if (fields == 2) files = {t[1]};
      if (fields == 4) files = {t[1], t[3]};
      if (fields == 9) files = {t[8]};
      for (const auto& f : files) {
        const cv::Mat image = cv::imread((dir / f), cv::IMREAD_UNCHANGED);
        INFO(index << ": " << f);
        REQUIRE(!image.empty());
        CHECK(image.cols == 320);
        CHECK(image.rows == 240);
        ++checked;
      }
    }
  }
  CHECK(checked >= 32);
  const auto gt = DataLines(dir / "groundtruth.txt");
  for (const auto& line : gt) {
    double stamp = 0.0;
    CHECK_NOTHROW(scene::Pose::FromTumLine(line, &stamp));
  }
}

}  // namespace
}  // namespace p2i::slam_sink
