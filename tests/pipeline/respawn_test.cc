/// @file respawn_test.cc
/// @brief The graph of tests/pipeline/respawn.yaml through `p2i launch`: the synthesizer is
/// SIGKILLed mid-run and respawned, render clients retry and succeed, the sink's sequence
/// accounting names the lost views and everything it acknowledged is on disk and readable.
#include <signal.h>

#include <chrono>
#include <set>
#include <string>
#include <thread>

#include <catch2/catch.hpp>
#include <opencv2/imgcodecs.hpp>

#include "convert/pose.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/raw_publisher.h"
#include "nodes/runtime/service_client.h"
#include "scene/trajectory.h"
#include "tests/pipeline/pipeline_test_util.h"

namespace p2i::pipeline {
namespace {

using namespace std::chrono_literals;
using testing::Clock;
using testing::LaunchedGraph;

using testing::RenderClient;

msgs::pb::RenderRequest Request(const std::vector<scene::StampedPose>& sweep, size_t i, int n) {
  msgs::pb::RenderRequest r;
  for (int k = 0; k < n; ++k) convert::ToMsg(sweep[(i + k) % sweep.size()].pose, r.add_poses());
  return r;
}

/// One call (the client retries internally); the reply must be ok with one view per pose.
bool RenderOk(RenderClient* client, const msgs::pb::RenderRequest& request,
              msgs::RenderReplyMsg* reply, std::string* error) {
  if (!client->Call(request, reply, error)) return false;
  if (!reply->meta.ok()) {
    *error = reply->meta.error();
    return false;
  }
  return reply->meta.views_size() == request.poses_size() &&
         reply->images.size() == 2u * request.poses_size();
}

// long-function: one scenario on one launched graph across a synthesizer kill and
// respawn; the sink's accounting of lost and kept views spans both processes.
TEST_CASE("launched graph: the synthesizer is killed and respawned, clients retry, the sink "
          "accounts for lost views and keeps everything it acknowledged",
          "[integration]") {
  LaunchedGraph graph;
  graph.Start(p2i::testing::SourceDir() + "/tests/pipeline/respawn.yaml");
  const std::string summary_path = graph.Out() + "/summary.json";
  const auto sweep = scene::GenerateArmSweep({});

  runtime::ServiceClientOptions client_options;
  client_options.timeout = 1000ms;
  client_options.retries = 30;  // covers start-up and a respawn (each attempt 1 s)
  RenderClient client("/render", "/pipeline_test", client_options);
  msgs::RenderReplyMsg reply;
  std::string error;
  INFO(graph.Log());
  REQUIRE(RenderOk(&client, Request(sweep, 0, 2), &reply, &error));
  CHECK(reply.images[0].width == 32);

  // Views with deliberate sequence gaps on the sink's second endpoint.
  runtime::PublisherOptions inject_options;
  inject_options.endpoint = "ipc://" + graph.Run() + "/inject.views.ipc";
  auto raw = std::make_shared<runtime::RawPublisher>("/views", "View", "/pipeline_test",
                                                     inject_options);
  runtime::Publisher<msgs::View> injector(raw, "/pipeline_test");
  msgs::View view;
  view.meta.mutable_pose()->CopyFrom(reply.meta.views(0).pose());
  view.meta.set_coverage(reply.meta.views(0).coverage());
  view.meta.set_method("test");
  view.rgb = reply.images[0];
  view.depth = reply.images[1];
  const std::string test_source = "/pipeline_test@/views";
  uint64_t seq = 0;
  auto publish = [&] {
    view.meta.mutable_header()->set_capture_stamp_ns(runtime::NowNs());
    injector.Publish(view);
    ++seq;
  };
  // Until the sink has seen us (slow joiner), then the gaps.
  bool joined = false;
  for (auto deadline = Clock::now() + 30s; !joined && Clock::now() < deadline;) {
    publish();
    std::this_thread::sleep_for(100ms);
    const auto s = testing::ReadJson(summary_path);
    joined = !s.is_null() && s["sequences"].contains(test_source);
  }
  REQUIRE(joined);
  std::set<uint64_t> expected_missing;
  for (int burn : {3, 0, 1, 0}) {  // skip 3 numbers, publish, publish, skip 1, publish
    for (int b = 0; b < burn; ++b) {
      seq = raw->NextSeq();  // a number that is never sent
      expected_missing.insert(seq);
    }
    publish();
    std::this_thread::sleep_for(20ms);
  }

  // The synthesizer has written views through the sink, then dies.
  const std::string synth_source = "/synthesizer@/views";
  auto synth_written = [&](const std::string& key) -> uint64_t {
    const auto s = testing::ReadJson(summary_path);
    if (s.is_null() || !s["sequences"].contains(key)) return 0;
    return s["sequences"][key]["received"].get<uint64_t>();
  };
  for (auto deadline = Clock::now() + 30s; synth_written(synth_source) < 5 && Clock::now() < deadline;)
    std::this_thread::sleep_for(100ms);
  REQUIRE(synth_written(synth_source) >= 5);
  const int old_pid = testing::RegisteredPid(graph.Run(), "service", "render");
  REQUIRE(old_pid > 0);
  REQUIRE(::kill(old_pid, SIGKILL) == 0);

  // Clients keep calling: every call succeeds (after retries) and is served by the new process.
  for (int i = 0; i < 5; ++i) {
    INFO("call " << i << ": " << error);
    CHECK(RenderOk(&client, Request(sweep, 10 * i, 3), &reply, &error));
  }
  CHECK(client.Raw().Stats().timeouts.load() >= 1);  // the killed server's calls timed out
  const int new_pid = testing::RegisteredPid(graph.Run(), "service", "render");
  CHECK(new_pid > 0);
  CHECK(new_pid != old_pid);

  // The respawned synthesizer's views reach the sink as a new epoch of the same source.
  for (auto deadline = Clock::now() + 30s;
       synth_written(synth_source + "#1") < 5 && Clock::now() < deadline;)
    std::this_thread::sleep_for(100ms);
  CHECK(synth_written(synth_source + "#1") >= 5);

  // Shutdown: the launcher reports the synthesizer's death (exit code 1: a node was killed by
  // a signal it did not send) after it respawned it; the sink flushes.
  const int code = graph.Stop();
  const std::string log = graph.Log();
  CHECK(code == 1);
  CHECK(log.find("respawning") != std::string::npos);

  const auto summary = testing::ReadJson(summary_path);
  REQUIRE(!summary.is_null());
  INFO(summary.dump(1));
  if (std::getenv("P2I_TEST_VERBOSE")) std::fprintf(stderr, "%s\n%s\n", summary.dump(1).c_str(), log.c_str());
  // Exactly the numbers the test skipped are reported lost for its source.
  const auto& mine = summary["sequences"][test_source];
  std::set<uint64_t> missing;
  for (const auto& range : mine["missing"])
    for (uint64_t s = range[0].get<uint64_t>(); s <= range[1].get<uint64_t>(); ++s)
      missing.insert(s);
  CHECK(missing == expected_missing);
  CHECK(mine["missing_count"].get<uint64_t>() == expected_missing.size());
  CHECK(mine["last_seq"].get<uint64_t>() == seq);
  // Every epoch's accounting adds up: received + missing = the numbers in its window.
  uint64_t missing_total = 0, received_total = 0;
  int synth_epochs = 0;
  for (const auto& [key, a] : summary["sequences"].items()) {
    CHECK(a["received"].get<uint64_t>() + a["missing_count"].get<uint64_t>() ==
          a["last_seq"].get<uint64_t>() - a["first_seq"].get<uint64_t>() + 1);
    missing_total += a["missing_count"].get<uint64_t>();
    received_total += a["received"].get<uint64_t>();
    if (key.rfind(synth_source, 0) == 0) ++synth_epochs;
  }
  CHECK(synth_epochs == 2);
  CHECK(summary["total_missing"].get<uint64_t>() == missing_total);

  // Everything acknowledged is listed once and readable on disk.
  const auto frames = testing::ReadIndex(graph.Out() + "/frames.txt");
  const auto rgb = testing::ReadIndex(graph.Out() + "/rgb.txt");
  const auto depth = testing::ReadIndex(graph.Out() + "/depth.txt");
  const uint64_t written = summary["frames_written"].get<uint64_t>();
  CHECK(frames.size() == written);
  CHECK(rgb.size() == written);
  CHECK(depth.size() == written);
  CHECK(written + summary["duplicates"].get<uint64_t>() == received_total);
  for (size_t i = 0; i < rgb.size(); ++i) {
    REQUIRE(rgb[i].size() == 2);
    REQUIRE(depth[i].size() == 2);
    const cv::Mat c = cv::imread(graph.Out() + "/" + rgb[i][1], cv::IMREAD_UNCHANGED);
    const cv::Mat d = cv::imread(graph.Out() + "/" + depth[i][1], cv::IMREAD_UNCHANGED);
    INFO(rgb[i][1] << " / " << depth[i][1]);
    REQUIRE(c.type() == CV_8UC3);
    REQUIRE(d.type() == CV_16UC1);
    CHECK(c.cols == 32);
    CHECK(d.rows == 32);
  }
  // The test's own views that arrived are all listed under their seq numbers.
  std::set<uint64_t> listed;
  for (const auto& f : frames)
    if (f.size() > 2 && f[1] == test_source) listed.insert(std::stoull(f[2]));
  CHECK(listed.size() == mine["received"].get<uint64_t>());
  for (uint64_t s : expected_missing) CHECK(listed.count(s) == 0);
}

}  // namespace
}  // namespace p2i::pipeline
