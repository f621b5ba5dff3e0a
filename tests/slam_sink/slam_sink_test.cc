/// @file slam_sink_test.cc
/// @brief SlamSink: policy flag/drop, duplicates, sequence gaps and summary.json.
#include "nodes/slam_sink/slam_sink.h"

#include <fstream>

#include <opencv2/imgproc.hpp>

#include <catch2/catch.hpp>

#include "scene/tum_rgbd.h"
#include "tests/slam_sink/sink_test_util.h"

namespace p2i::slam_sink {
namespace {

using testing::BasePose;
using testing::DataLines;
using testing::Moved;
using testing::RenderedFrame;
using testing::SmallCamera;
using testing::Split;
using testing::TempDir;

// seq 0 good, seq 1 claims a pose 10 cm off, seq 2 lost, seq 3 good, seq 3 again (duplicate),
// plus one real frame between them.
std::vector<SinkFrame> Stream() {
  const scene::Pose a = BasePose();
  std::vector<SinkFrame> frames;
  frames.push_back(RenderedFrame(a, 1.0, 0));
  SinkFrame wrong = RenderedFrame(Moved(a, 0.02, 0.0, 0.0, 0.5), 1.1, 1);
  wrong.pose = Moved(wrong.pose, 0.1, 0.0, 0.0);
  frames.push_back(wrong);
  SinkFrame real = RenderedFrame(Moved(a, 0.01, 0.0, 0.0), 1.15, 40);
  real.synthetic = false;
  real.source = "/camera";
  frames.push_back(real);
  frames.push_back(RenderedFrame(Moved(a, 0.04, 0.0, 0.0, 1.0), 1.3, 3));
  frames.push_back(frames.back());
  return frames;
}

nlohmann::json ReadJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  return nlohmann::json::parse(in);
}

TEST_CASE("SlamSink with policy flag writes every frame and marks the failing one", "[unit]") {
  TempDir dir("flag");
  SlamSinkOptions options;
  options.writer.out_dir = dir.path();
  options.policy = "flag";
  {
    SlamSink sink(options, SmallCamera());
    const auto frames = Stream();
    std::vector<SlamSink::Outcome> outcomes;
    for (const auto& f : frames) outcomes.push_back(sink.Process(f));
    CHECK(outcomes[1].check.status == CheckResult::Status::kFail);
    CHECK(outcomes[1].written);
    CHECK(outcomes[3].check.status == CheckResult::Status::kPass);
    CHECK(outcomes[3].gap == 1);
    CHECK(outcomes[4].duplicate);
    CHECK_FALSE(outcomes[4].written);
    sink.Close();
  }
  const auto lines = DataLines(dir / "frames.txt");
  REQUIRE(lines.size() == 4);
  std::map<std::string, std::string> check_by_seq;
  for (const auto& line : lines) {
    const auto t = Split(line);
    check_by_seq[t[1] + ":" + t[2]] = t[4];
  }
  CHECK(check_by_seq["/synthesizer:1"] == "fail");
  CHECK(check_by_seq["/synthesizer:3"] == "pass");
  CHECK(check_by_seq["/camera:40"] == "real");

  const nlohmann::json summary = ReadJson(dir / "summary.json");
  CHECK(summary["frames_written"] == 4);
  CHECK(summary["synthetic_written"] == 3);
  CHECK(summary["real_written"] == 1);
  CHECK(summary["duplicates"] == 1);
  CHECK(summary["check"]["flagged"] == 1);
  CHECK(summary["check"]["dropped"] == 0);
  CHECK(summary["check"]["checked"] == 2);
  CHECK(summary["check"]["pass_rate"].get<double>() == Approx(0.5));
  CHECK(summary["check"]["translation_error_m"]["count"] == 2);
  CHECK(summary["sequences"]["/synthesizer"]["missing"] == nlohmann::json::parse("[[2,2]]"));
  CHECK(summary["sequences"]["/camera"]["missing_count"] == 0);
  CHECK(summary["total_missing"] == 1);

  // The sequence reads back with the project's TUM reader, calibration included.
  scene::TumRgbdOptions read_options;
  read_options.max_pose_gap = 1.0;
  const scene::DatasetIndex index = scene::ReadTumRgbd(dir.path(), read_options);
  CHECK(index.size() == 4);
  CHECK(index.camera().fx() == Approx(SmallCamera().fx()));
  const scene::RgbdSample first = index.Load(0);
  const SinkFrame expected = Stream().front();
  CHECK(cv::norm(first.rgb, expected.rgb, cv::NORM_INF) == 0.0);
  CHECK(first.pose.equals(expected.pose, 1e-6));
}

TEST_CASE("SlamSink with policy drop does not write failing frames", "[unit]") {
  TempDir dir("drop");
  SlamSinkOptions options;
  options.writer.out_dir = dir.path();
  options.policy = "drop";
  options.write_real = false;
  {
    SlamSink sink(options, SmallCamera());
    for (const auto& f : Stream()) sink.Process(f);
    sink.Close();
  }
  const auto lines = DataLines(dir / "frames.txt");
  REQUIRE(lines.size() == 2);
  for (const auto& line : lines) {
    CHECK(Split(line)[4] != "fail");
    CHECK(Split(line)[3] == "synthetic");
  }
  const nlohmann::json summary = ReadJson(dir / "summary.json");
  CHECK(summary["check"]["dropped"] == 1);
  CHECK(summary["real_skipped"] == 1);
  CHECK(DataLines(dir / "rgb.txt").size() == 2);
}

TEST_CASE("SlamSink without a camera writes everything unchecked", "[unit]") {
  TempDir dir("nocam");
  SlamSinkOptions options;
  options.writer.out_dir = dir.path();
  SlamSink sink(options, std::nullopt);
  for (const auto& f : Stream()) sink.Process(f);
  sink.Close();
  const nlohmann::json summary = ReadJson(dir / "summary.json");
  CHECK(summary["check"]["enabled"] == false);
  CHECK(summary["frames_written"] == 4);
}

TEST_CASE("SlamSinkOptions parse YAML and name unknown keys", "[unit]") {
  const SlamSinkOptions o = SlamSinkOptions::FromYaml(
      YAML::Load("{out_dir: /tmp/x, policy: drop, max_translation_error_m: 0.05, "
                 "odometry_method: icp}"),
      "test.yaml");
  CHECK(o.writer.out_dir == "/tmp/x");
  CHECK(o.policy == "drop");
  CHECK(o.checker.max_translation_error_m == 0.05);
  CHECK(o.checker.method == "icp");
  CHECK_THROWS_WITH(SlamSinkOptions::FromYaml(YAML::Load("{out_dir: /tmp/x, polcy: drop}"),
                                              "test.yaml"),
                    Catch::Contains("polcy") && Catch::Contains("test.yaml"));
  CHECK_THROWS_WITH(SlamSinkOptions::FromYaml(YAML::Load("{out_dir: /tmp/x, policy: keep}"),
                                              "test.yaml"),
                    "slam_sink: policy must be flag or drop (got 'keep'); policy:=flag writes "
                    "failing frames, marked; policy:=drop does not write them");
}

}  // namespace
}  // namespace p2i::slam_sink

namespace p2i::slam_sink {

TEST_CASE("SlamSink's camera_info.yaml matches the views it writes", "[unit]") {
  TempDir dir("camera_size");
  SlamSinkOptions options;
  options.writer.out_dir = dir.path();
  options.check = false;
  SlamSink sink(options, SmallCamera(640, 480));  // a 640x480 calibration, 160x120 views
  const scene::Pose a = BasePose();
  CHECK(sink.Process(RenderedFrame(a, 1.0, 0)).written);
  const auto written = scene::CameraInfo::FromYamlFile(dir.path() + "/camera_info.yaml");
  CHECK(written.image_width == 160);
  CHECK(written.image_height == 120);
  CHECK(written.fx() == Approx(SmallCamera(640, 480).fx() / 4));
  // A later view of another size is refused, naming both sizes.
  SinkFrame other = RenderedFrame(Moved(a, 0.01, 0, 0), 1.1, 1);
  cv::resize(other.rgb, other.rgb, cv::Size(80, 60));
  cv::resize(other.depth, other.depth, cv::Size(80, 60), 0, 0, cv::INTER_NEAREST);
  CHECK_THROWS_WITH(sink.Process(other), Catch::Contains("80x60") && Catch::Contains("160x120"));
  sink.Close();
  // The sequence reads back with p2i's own reader.
  CHECK(scene::ReadTumRgbd(dir.path()).size() == 1);
}

}  // namespace p2i::slam_sink
