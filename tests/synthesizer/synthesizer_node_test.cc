/// @file synthesizer_node_test.cc
/// @brief p2i_synthesizer as a process (nearest keyframe on builtin:small_office at 64x64):
/// render service clients and topic mode.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "msgs/codec.h"
#include "convert/image.h"
#include "convert/pose.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/raw_publisher.h"
#include "nodes/runtime/raw_subscriber.h"
#include "nodes/runtime/service_client.h"
#include "scene/trajectory.h"
#include "tests/runtime/test_util.h"
#include "tests/process_util.h"
#include "tests/test_paths.h"

namespace p2i::nodes {
namespace {

using p2i::testing::Process;
using runtime::testing::ScopedRunDir;

// long-function: one scenario on one synthesizer process (start-up renders its training frames
// once): the render service, a refused request, then topic mode, the node serving throughout.
TEST_CASE("p2i_synthesizer serves nearest-keyframe views over the render service and topics",
          "[integration]") {
  ScopedRunDir run_dir;
  Process synth({p2i::testing::BinDir() + "/p2i_synthesizer", "method:=nearest",
                 "dataset:=builtin:small_office", "width:=64", "height:=64",
                 "dataset_stride:=4", "max_poses:=8", "status_period:=0"});
  REQUIRE(synth.pid() > 0);

  const auto sweep = scene::GenerateArmSweep({});
  REQUIRE(sweep.size() > 40);
  runtime::ServiceClientOptions client_options;
  client_options.timeout = std::chrono::milliseconds(3000);
  client_options.retries = 10;  // the node renders its training frames before it serves
  runtime::ServiceClient<msgs::pb::RenderRequest, msgs::RenderReplyMsg> client("/render", "test",
                                                                               client_options);
  msgs::pb::RenderRequest request;
  request.set_request_id(5);
  convert::ToMsg(sweep[0].pose, request.add_poses());   // a training pose (stride 4 keeps index 0)
  convert::ToMsg(sweep[40].pose, request.add_poses());  // another one
  convert::ToMsg(scene::Pose(sweep[2].pose.translation() + Eigen::Vector3d(0.0, 0.0, 2.0),
                    sweep[2].pose.rotation()),
        request.add_poses());  // 2 m above the sweep: poorly covered
  msgs::RenderReplyMsg reply;
  std::string error;
  REQUIRE(client.Call(request, &reply, &error));
  INFO(reply.meta.error());
  REQUIRE(reply.meta.ok());
  CHECK(reply.meta.request_id() == 5);
  REQUIRE(reply.meta.views_size() == 3);
  REQUIRE(reply.images.size() == 6);
  for (int i = 0; i < 3; ++i) {
    CHECK(reply.images[2 * i].encoding == msgs::pb::RGB8);
    CHECK(reply.images[2 * i].width == 64);
    CHECK(reply.images[2 * i].height == 64);
    CHECK(reply.images[2 * i + 1].encoding == msgs::pb::DEPTH32F);
    CHECK(reply.images[2 * i + 1].width == 64);
    CHECK(reply.images[2 * i + 1].height == 64);
    CHECK(reply.meta.views(i).method() == "nearest");
    // A rendered office, not an empty image.
    const cv::Mat depth = convert::ToMat(reply.images[2 * i + 1]);
    CHECK(cv::countNonZero(depth > 0.0f) > 64 * 64 / 2);
  }
  CHECK(reply.meta.views(0).coverage() == Approx(1.0));
  CHECK(reply.meta.views(1).coverage() == Approx(1.0));
  CHECK(reply.meta.views(2).coverage() < 0.5);
  // The two training poses give different frames.
  CHECK(cv::norm(convert::ToMat(reply.images[0]), convert::ToMat(reply.images[2]), cv::NORM_L1) > 0.0);

  // Too many poses: refused with a reason, and the node keeps serving.
  msgs::pb::RenderRequest big;
  for (int i = 0; i < 9; ++i) convert::ToMsg(sweep[i].pose, big.add_poses());
  REQUIRE(client.Call(big, &reply, &error));
  CHECK_FALSE(reply.meta.ok());
  CHECK(reply.meta.error().find("max_poses") != std::string::npos);
  REQUIRE(client.Call(request, &reply, &error));
  CHECK(reply.meta.ok());

  // Topic mode: a PoseRequest on planned_poses comes back as a View on views.
  runtime::RawSubscriber views("/views", {});
  runtime::PublisherOptions pub_options;
  runtime::Publisher<msgs::pb::PoseRequest> planned(
      std::make_shared<runtime::RawPublisher>("/planned_poses", "PoseRequest", "/test",
                                              pub_options),
      "/test");
  msgs::View view;
  bool got = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!got && std::chrono::steady_clock::now() < deadline) {
    msgs::pb::PoseRequest pr;
    pr.set_request_id(77);
    convert::ToMsg(sweep[8].pose, pr.mutable_pose());
    planned.Publish(pr);  // repeated until the subscription has joined
    msgs::WireMessage wire;
    msgs::pb::Header header;
    if (views.Receive(&wire, &header, std::chrono::milliseconds(200))) {
      got = msgs::Decode(wire, &view, &error);
    }
  }
  REQUIRE(got);
  CHECK(view.meta.header().request_id() == 77);
  CHECK(view.rgb.width == 64);
  CHECK(view.depth.height == 64);
  CHECK(view.meta.coverage() == Approx(1.0));

  CHECK(synth.Terminate() == 0);
}

}  // namespace
}  // namespace p2i::nodes
