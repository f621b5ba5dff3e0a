/// @file monitor_node_test.cc
/// @brief MonitorNode in-process: served views and a compared method's views scored against the
/// sim ground truth, the free baselines on the same poses, the summary JSON written when the
/// duration is over.
#include <catch2/catch.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "convert/camera_info.h"
#include "convert/image.h"
#include "convert/pose.h"
#include "nodes/monitor/monitor_node.h"
#include "nodes/runtime/shutdown.h"
#include "scene/image_ops.h"
#include "scene/trajectory.h"
#include "tests/runtime/test_util.h"
#include "tests/temp_dir.h"

using namespace p2i;

namespace {

msgs::View MakeView(const scene::RgbdSample& s, const std::string& method) {
  msgs::View v;
  convert::ToMsg(s.pose, v.meta.mutable_pose());
  v.meta.set_method(method);
  v.meta.set_model_version(3);
  v.rgb = convert::ToImage(s.rgb);
  v.depth = convert::ToImage(s.depth);
  return v;
}

}  // namespace

// long-function: one scenario: the graph's three publishers, the spin until the summary, checks.
TEST_CASE("MonitorNode: served and compared views beside the baselines in summary.json",
          "[unit]") {
  runtime::Shutdown::ResetForTesting();
  runtime::testing::ScopedRunDir run_dir;
  const p2i::testing::TempDir dir("monitor_node");
  const std::string summary = dir / "summary.json";
  const scene::SimScene sim = scene::SimScene::BuiltIn("small_office");
  const scene::CameraInfo cam = scene::SimScene::DefaultCamera(64, 48);
  const auto sweep = scene::GenerateArmSweep({});

  runtime::Node graph("graph", runtime::NodeArgs::Parse(std::vector<std::string>{}));
  auto views = graph.Advertise<msgs::View>("views");
  auto compare = graph.Advertise<msgs::View>("compare_views");
  auto frames = graph.Advertise<msgs::RgbdFrame>("rgbd");
  nodes::MonitorNode monitor(runtime::NodeArgs::Parse(std::vector<std::string>{
      "duration:=2.5", "scene:=builtin:small_office", "camera_width:=64", "camera_height:=48",
      "lpips_weights:=/nonexistent", "summary_file:=" + summary}));
  graph.Start();
  monitor.Start();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  size_t i = 0;
  while (!std::filesystem::exists(summary) && std::chrono::steady_clock::now() < deadline) {
    // A captured keyframe at pose i; the views are at the pose of the loop before, so they
    // arrive after their keyframe (another socket) and the nearest keyframe is exact.
    msgs::RgbdFrame f;
    convert::ToMsg(sweep[(7 * i) % sweep.size()].pose, f.meta.mutable_pose());
    convert::ToMsg(scene::CenterCropResizeCamera(cam, 32, 32), f.meta.mutable_camera_info());
    f.rgb = convert::ToImage(cv::Mat(32, 32, CV_8UC3, cv::Scalar(0, 0, 0)));
    f.depth = convert::ToImage(cv::Mat(32, 32, CV_32FC1, cv::Scalar(1.0f)));
    frames->Publish(f);
    if (i++ == 0) continue;
    const scene::Pose pose = sweep[(7 * (i - 2)) % sweep.size()].pose;
    // Served: the exact view (what a perfect method renders), with an observed fraction.
    scene::RgbdSample exact = scene::CenterCropResizeSample(sim.Render(pose, cam), 32, 32);
    exact.pose = pose;
    msgs::View served = MakeView(exact, "fusion");
    served.meta.set_observed_fraction(0.75);
    views->Publish(served);
    // Compared: one grey image for every pose (a collapsed model).
    scene::RgbdSample grey = exact;
    grey.rgb = cv::Mat(32, 32, CV_8UC3, cv::Scalar(128, 128, 128));
    grey.depth = cv::Mat(32, 32, CV_32FC1, cv::Scalar(2.0f));
    compare->Publish(MakeView(grey, "p2i"));
    for (int k = 0; k < 10; ++k) {
      graph.SpinOnce(std::chrono::milliseconds(1));
      monitor.SpinOnce(std::chrono::milliseconds(5));
    }
  }
  INFO(monitor.MakeStatus().DebugString());  // a `malformed` count names a bad test message
  REQUIRE(std::filesystem::exists(summary));
  nlohmann::json j;
  std::ifstream(summary) >> j;
  INFO(j.dump(2));
  CHECK(j["method"] == "fusion");
  CHECK(j["views_scored"].get<int>() >= 3);
  CHECK(j["psnr_db_median"].get<double>() > 60.0);  // exact views
  CHECK(j["observed_fraction_median"].get<double>() == Approx(0.75));
  CHECK(j["depth_absrel_median"].get<double>() < 1e-3);
  // The baselines on the same poses: views at captured poses, so the nearest keyframe is exact.
  CHECK(j["nearest_keyframe_psnr_db_median"].get<double>() > 60.0);
  CHECK(j["depth_warp_psnr_db_median"].is_number());
  REQUIRE(j.contains("compare"));
  CHECK(j["compare"]["method"] == "p2i");
  CHECK(j["compare"]["views_scored"].get<int>() >= 3);
  CHECK(j["compare"]["psnr_db_median"].get<double>() < 20.0);
  CHECK(j["compare"]["depth_absrel_median"].get<double>() > 0.05);
}
