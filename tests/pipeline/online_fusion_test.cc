/// @file online_fusion_test.cc
/// @brief tests/pipeline/online_fusion.yaml through `p2i launch`: camera frames mapped online by
/// the trainer node (method fusion), versions hot-swapped by the synthesizer while it serves
/// /render, views covering the mapped room.
#include <chrono>
#include <string>

#include <catch2/catch.hpp>

#include "convert/image.h"
#include "convert/pose.h"
#include "nodes/runtime/service_client.h"
#include "scene/trajectory.h"
#include "tests/pipeline/pipeline_test_util.h"

namespace p2i::pipeline {
namespace {

using namespace std::chrono_literals;
using testing::LaunchedGraph;
using testing::RenderClient;

}  // namespace

TEST_CASE("launched graph: frames mapped online, fusion versions hot-swapped while serving",
          "[integration]") {
  LaunchedGraph graph;
  graph.Start(p2i::testing::SourceDir() + "/tests/pipeline/online_fusion.yaml");
  testing::StatusWatcher status({"/mapper", "/synthesizer"});
  // A few versions published and the synthesizer serving one of them.
  const bool serving = status.WaitFor(
      [&] {
        return status.Counter("/mapper", "versions_published") >= 3 &&
               status.Value("/synthesizer", "model_version") >= 2;
      },
      60s);
  // Built now, after the wait (INFO's text is fixed when it runs): what the nodes reported and
  // logged by then, for a failure of this or any later check.
  INFO("statuses after the wait:\n" << status.Describe() << "launch log:\n" << graph.Log());
  REQUIRE(serving);
  CHECK(status.Value("/mapper", "frames_integrated") >= 15);
  CHECK(status.Value("/mapper", "keyframes") >= 2);
  CHECK(status.Value("/mapper", "frames_rejected") == 0);
  // Every version the synthesizer started loading was still there (the mapper prunes none younger
  // than keep_seconds; with keep_versions 2 and a version every 0.5 s, 3 of 4 runs lost one
  // before that, and a busy box could lose them all).
  CHECK(status.Counter("/synthesizer", "swap_failures") == 0);

  // The pose of a frame the camera captured (the first sweep), rendered from the map.
  const auto sweep = scene::GenerateAdjacentSweeps({}).at(0);
  runtime::ServiceClientOptions client_options;
  client_options.timeout = 3000ms;
  client_options.retries = 10;
  RenderClient client("/render", "/online_fusion_test", client_options);
  msgs::pb::RenderRequest request;
  convert::ToMsg(sweep[5].pose, request.add_poses());
  msgs::RenderReplyMsg reply;
  std::string error;
  REQUIRE(client.Call(request, &reply, &error));
  INFO(reply.meta.error());
  REQUIRE(reply.meta.ok());
  REQUIRE(reply.images.size() == 2);
  CHECK(reply.meta.views(0).method() == "fusion");
  CHECK(reply.meta.views(0).model_version() >= 2);
  CHECK(reply.images[0].width == 32);
  REQUIRE(reply.meta.views(0).has_observed_fraction());
  CHECK(reply.meta.views(0).observed_fraction() > 0.8);
  const cv::Mat depth = convert::ToMat(reply.images[1]);
  CHECK(cv::countNonZero(depth > 0.0f) > 32 * 32 * 9 / 10);

  // Later versions keep coming and are swapped in.
  const double served = status.Value("/synthesizer", "model_version");
  REQUIRE(status.WaitFor([&] { return status.Value("/synthesizer", "model_version") > served; },
                         30s));
}

}  // namespace p2i::pipeline
