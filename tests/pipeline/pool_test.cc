/// @file pool_test.cc
/// @brief tests/pipeline/pool.yaml through `p2i launch`: p2i_pool spreads /render over two
/// synthesizers; one is SIGKILLed mid-run and every request is still answered (the broker
/// re-queues the dead worker's request, the client retries), by the survivor from then on.
#include <signal.h>

#include <chrono>
#include <map>
#include <string>

#include <catch2/catch.hpp>

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

TEST_CASE("launched pool: /render spread over two synthesizers, one SIGKILLed mid-run, no "
          "request lost",
          "[integration]") {
  LaunchedGraph graph;
  graph.Start(p2i::testing::SourceDir() + "/tests/pipeline/pool.yaml");
  const auto sweep = scene::GenerateArmSweep({});
  runtime::ServiceClientOptions client_options;
  client_options.timeout = 1000ms;
  client_options.retries = 30;  // start-up of the synthesizers, and the kill
  RenderClient client("/render", "/pool_test", client_options);
  INFO(graph.Log());

  testing::StatusWatcher status({"/pool"});
  // Both workers joined: the pool reports two.
  REQUIRE(status.WaitFor([&] { return status.Value("/pool", "pool_workers") >= 2; }, 30s));

  std::map<std::string, int> served;
  const int kCalls = 40, kKillAt = 12;
  int ok = 0;
  for (int i = 0; i < kCalls; ++i) {
    if (i == kKillAt) {
      const int pid = testing::RegisteredPid(graph.Run(), "topic", "a.synthesizer.status");
      REQUIRE(pid > 0);
      REQUIRE(::kill(pid, SIGKILL) == 0);
    }
    msgs::pb::RenderRequest request;
    convert::ToMsg(sweep[(3 * i) % sweep.size()].pose, request.add_poses());
    msgs::RenderReplyMsg reply;
    std::string error;
    const bool got = client.Call(request, &reply, &error) && reply.meta.ok() &&
                     reply.images.size() == 2;
    INFO("call " << i << ": " << error);
    CHECK(got);
    if (!got) continue;
    ++ok;
    ++served[reply.meta.header().publisher() + (i < kKillAt ? " before" : " after")];
  }
  CHECK(ok == kCalls);
  // Before the kill both took turns; after it only the survivor answered.
  CHECK(served["/a/synthesizer before"] > 0);
  CHECK(served["/b/synthesizer before"] > 0);
  CHECK(served["/a/synthesizer after"] == 0);
  CHECK(served["/b/synthesizer after"] == kCalls - kKillAt);
  status.WaitFor([&] { return status.Counter("/pool", "pool_workers_lost") >= 1; }, 10s);
  CHECK(status.Counter("/pool", "pool_workers_lost") >= 1);
  CHECK(status.Value("/pool", "pool_workers") == 1);
  graph.Stop();
}

}  // namespace p2i::pipeline
