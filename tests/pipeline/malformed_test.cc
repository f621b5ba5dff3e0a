/// @file malformed_test.cc
/// @brief tests/pipeline/graph.yaml through `p2i launch` (camera, trainer with a tiny P2I-NET,
/// synthesizer on the real p2i path, slam_sink, monitor): malformed messages on every topic and
/// service the nodes read are dropped and counted (NodeStatus), one by one, and afterwards the
/// graph still serves valid traffic: the trainer publishes versions, the synthesizer swaps them
/// in and renders with them, the sink writes, every node exits 0.
#include <chrono>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <zmq.hpp>

#include "msgs/codec.h"
#include "convert/camera_info.h"
#include "convert/image.h"
#include "convert/pose.h"
#include "nodes/runtime/endpoints.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/raw_publisher.h"
#include "nodes/runtime/service_client.h"
#include "nodes/runtime/zmq_context.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"
#include "tests/pipeline/pipeline_test_util.h"

namespace p2i::pipeline {
namespace {

using namespace std::chrono_literals;
using testing::Clock;
using testing::LaunchedGraph;
using testing::StatusWatcher;

/// A test-owned publisher of one topic at `endpoint` ("" = the topic's default endpoint):
/// stamps every valid message it builds with its own fresh sequence number.
class Injector {
 public:
  Injector(const std::string& topic, const std::string& endpoint) {
    runtime::PublisherOptions o;
    o.endpoint = endpoint;
    raw_ = std::make_shared<runtime::RawPublisher>(topic, "any", "/injector", o);
  }
  template <class T>
  msgs::WireMessage Valid(T msg) {
    msgs::pb::Header* h = msgs::MutableHeader(msg);
    h->set_seq(raw_->NextSeq());
    h->set_publish_stamp_ns(runtime::NowNs());
    if (h->capture_stamp_ns() == 0) h->set_capture_stamp_ns(runtime::NowNs());
    h->set_publisher("/injector");
    return msgs::Encode(msg);
  }
  void Send(const msgs::WireMessage& w) { raw_->Publish(w); }

 private:
  std::shared_ptr<runtime::RawPublisher> raw_;
};

/// Garbage, wrong type, truncated protobuf, an extra 8 MiB blob: each must fail to decode as T.
template <class T>
std::vector<std::pair<std::string, msgs::WireMessage>> BadMessages(Injector* inj, const T& right) {
  std::vector<std::pair<std::string, msgs::WireMessage>> out;
  msgs::WireMessage garbage;
  garbage.header = std::string("\x0a\xff\xff\xff\xff\x0f", 6) + std::string(58, '\xab');
  out.emplace_back("garbage bytes", garbage);
  msgs::pb::NodeStatus other;
  other.set_node("/not_what_you_expect");
  out.emplace_back("wrong type (NodeStatus)", inj->Valid(other));
  msgs::WireMessage truncated = inj->Valid(right);
  truncated.header.resize(truncated.header.size() / 2);
  out.emplace_back("truncated protobuf", truncated);
  msgs::WireMessage huge = inj->Valid(right);
  huge.blobs.push_back(std::make_shared<const msgs::Bytes>(size_t{8} << 20, uint8_t{0x5a}));
  out.emplace_back("extra 8 MiB blob", huge);
  for (const auto& [what, w] : out) {
    T decoded;
    std::string error;
    INFO(what);
    REQUIRE_FALSE(msgs::Decode(w, &decoded, &error));  // the test's bad input really is bad
  }
  return out;
}

// long-function: one scenario on one launched graph: malformed input on every topic and
// service, then valid traffic through the same nodes; the totals count every injection before.
TEST_CASE("launched graph: malformed messages on every topic and service are dropped and "
          "counted, and the nodes keep serving valid traffic",
          "[integration]") {
  LaunchedGraph graph;
  const std::string run = graph.Run();
  auto inject = [&](const std::string& topic) {
    return std::make_unique<Injector>("/" + topic, "ipc://" + run + "/inject." + topic + ".ipc");
  };
  // Bound before the graph starts, so every subscription is connected when the nodes are up.
  Injector pose("/pose", "");                  // the camera's only pose source
  Injector planned("/planned_pose", "");       // the synthesizer's only planned-pose source
  auto rgbd = inject("rgbd");                  // trainer, monitor
  auto camera_info = inject("camera_info");    // slam_sink
  auto model_version = inject("model_version");// synthesizer, monitor
  auto views = inject("views");                // slam_sink, monitor
  graph.Start(p2i::testing::SourceDir() + "/tests/pipeline/graph.yaml");
  INFO(graph.Log());

  const std::vector<std::string> nodes{"/camera", "/trainer", "/synthesizer", "/slam_sink",
                                       "/monitor"};
  StatusWatcher status(nodes);
  const auto sweep = scene::GenerateArmSweep({});
  size_t pose_index = 0;
  auto last_pose = Clock::now();
  bool feed_poses = true;
  auto tick = [&] {  // the camera renders one frame per pose it receives
    if (!feed_poses || Clock::now() - last_pose < 100ms) return;
    last_pose = Clock::now();
    msgs::pb::PoseStamped p;
    convert::ToMsg(sweep[pose_index++ % sweep.size()].pose, p.mutable_pose());
    pose.Send(pose.Valid(p));
  };
  auto wait_for = [&](const std::function<bool()>& cond, std::chrono::seconds timeout) {
    return status.WaitFor([&] { tick(); return cond(); }, timeout);
  };
  REQUIRE(wait_for([&] {
    for (const auto& n : nodes) if (!status.Has(n)) return false;
    return true;
  }, 60s));
  std::this_thread::sleep_for(300ms);
  status.Poll();
  const uint64_t accepted_before = status.Counter("/trainer", "frames_accepted");
  const uint64_t published_before = status.Counter("/camera", "frames_published");

  // Sends each message on its own and waits until every target node counted it as malformed.
  std::map<std::string, uint64_t> expected;
  for (const auto& n : nodes) expected[n] = status.Counter(n, "malformed");
  auto inject_all = [&](Injector* inj, const std::vector<std::pair<std::string, msgs::WireMessage>>& bad,
                        const std::vector<std::string>& targets, const std::string& topic) {
    for (const auto& [what, w] : bad) {
      for (const auto& t : targets) ++expected[t];
      inj->Send(w);
      const bool counted = wait_for([&] {
        for (const auto& t : targets)
          if (status.Counter(t, "malformed") < expected[t]) return false;
        return true;
      }, 15s);
      INFO(topic << ": " << what);
      for (const auto& t : targets) {
        INFO(t << " malformed " << status.Counter(t, "malformed") << ", expected " << expected[t]);
        CHECK(counted);
      }
    }
  };

  // Right-typed valid samples to break.
  const scene::SimScene sim = scene::SimScene::BuiltIn("small_office");
  const scene::CameraInfo cam = scene::SimScene::DefaultCamera(64, 48);
  const scene::RgbdSample sample = sim.Render(sweep[3].pose, cam, 0.0);
  msgs::RgbdFrame frame;
  convert::ToMsg(sample.pose, frame.meta.mutable_pose());
  frame.rgb = convert::ToImage(sample.rgb);
  frame.depth = convert::ToImage(sample.depth);
  convert::ToMsg(cam, frame.meta.mutable_camera_info());
  msgs::View view;
  convert::ToMsg(sample.pose, view.meta.mutable_pose());
  view.rgb = frame.rgb;
  view.depth = frame.depth;
  msgs::pb::CameraInfo info;
  convert::ToMsg(cam, &info);
  msgs::pb::PoseStamped pose_msg;
  convert::ToMsg(sweep[5].pose, pose_msg.mutable_pose());
  msgs::pb::PoseRequest request_msg;
  request_msg.set_request_id(1);
  convert::ToMsg(sweep[5].pose, request_msg.mutable_pose());
  msgs::pb::ModelVersion version_msg;
  version_msg.set_version(1);
  version_msg.set_checkpoint_path("/nonexistent.pt");

  feed_poses = false;  // the camera's pose subscription is latest-only: one message at a time
  inject_all(&pose, BadMessages(&pose, pose_msg), {"/camera"}, "/pose");
  feed_poses = true;
  inject_all(&planned, BadMessages(&planned, request_msg), {"/synthesizer"}, "/planned_pose");
  inject_all(rgbd.get(), BadMessages(rgbd.get(), frame), {"/trainer", "/monitor"}, "/rgbd");
  inject_all(camera_info.get(), BadMessages(camera_info.get(), info), {"/slam_sink"},
             "/camera_info");
  auto huge_version = BadMessages(model_version.get(), version_msg);
  msgs::pb::ModelVersion absurd = version_msg;
  absurd.set_width(1000000);  // a size no image can have
  huge_version.emplace_back("width 1000000", model_version->Valid(absurd));
  inject_all(model_version.get(), huge_version, {"/synthesizer", "/monitor"}, "/model_version");
  inject_all(views.get(), BadMessages(views.get(), view), {"/slam_sink", "/monitor"}, "/views");

  // Well-formed but unusable: counted by the node, nothing else happens.
  msgs::RgbdFrame no_info = frame;
  no_info.meta.set_camera_info_id("/elsewhere/camera_info");  // the trainer needs it inline
  const uint64_t no_info_before = status.Counter("/trainer", "frames_without_camera_info");
  rgbd->Send(rgbd->Valid(no_info));
  CHECK(wait_for([&] {
    return status.Counter("/trainer", "frames_without_camera_info") == no_info_before + 1;
  }, 15s));
  const double serving_before = status.Value("/synthesizer", "model_version");
  msgs::pb::ModelVersion bogus;
  bogus.set_version(1000);  // far ahead of the trainer, and no such file
  bogus.set_checkpoint_path(run + "/no_such_checkpoint.pt");
  const uint64_t failures_before = status.Counter("/synthesizer", "swap_failures");
  model_version->Send(model_version->Valid(bogus));
  CHECK(wait_for([&] {
    return status.Counter("/synthesizer", "swap_failures") == failures_before + 1;
  }, 15s));

  // The render service: bad envelope, undecodable requests, a refused one.
  const std::string render_endpoint = runtime::DefaultEndpoint("service", "/render");
  {
    zmq::socket_t dealer(runtime::ZmqContext(), zmq::socket_type::dealer);
    dealer.set(zmq::sockopt::linger, 0);
    dealer.connect(render_endpoint);
    const uint64_t before = status.Counter("/synthesizer", "malformed");
    dealer.send(zmq::buffer(std::string("no envelope")), zmq::send_flags::none);
    CHECK(wait_for([&] { return status.Counter("/synthesizer", "malformed") == before + 1; },
                   15s));
  }
  runtime::ServiceClientOptions raw_options;
  raw_options.timeout = 5000ms;
  raw_options.retries = 0;
  runtime::RawServiceClient raw_client("/render", raw_options);
  msgs::pb::RenderRequest good_request;
  convert::ToMsg(sweep[7].pose, good_request.add_poses());
  Injector scratch("/scratch", "ipc://" + run + "/scratch.ipc");  // numbers the bad requests
  for (const auto& [what, w] : BadMessages(&scratch, good_request)) {
    const uint64_t before = status.Counter("/synthesizer", "request_errors");
    msgs::WireMessage reply;
    std::string error;
    INFO("render: " << what);
    CHECK_FALSE(raw_client.Call(w, &reply, &error));
    CHECK(error.find("malformed request") != std::string::npos);
    CHECK(wait_for([&] {
      return status.Counter("/synthesizer", "request_errors") == before + 1;
    }, 15s));
  }
  runtime::ServiceClientOptions client_options;
  client_options.timeout = 5000ms;
  client_options.retries = 2;
  runtime::ServiceClient<msgs::pb::RenderRequest, msgs::RenderReplyMsg> client(
      "/render", "/pipeline_test", client_options);
  msgs::pb::RenderRequest too_many;
  for (int i = 0; i < 17; ++i) convert::ToMsg(sweep[i].pose, too_many.add_poses());
  msgs::RenderReplyMsg reply;
  std::string error;
  REQUIRE(client.Call(too_many, &reply, &error));
  CHECK_FALSE(reply.meta.ok());
  CHECK(reply.meta.error().find("max_poses") != std::string::npos);

  // Totals: exactly what was injected (nothing else was malformed).
  status.Poll(300ms);
  for (const auto& n : nodes) {
    INFO(n);
    CHECK(status.Counter(n, "malformed") == expected[n] + (n == "/synthesizer" ? 1 : 0));
  }

  // Valid traffic afterwards. The trainer keeps accepting frames and publishing versions; the
  // synthesizer swaps in a newer one than it served before the bogus announcement and renders
  // with it through the real p2i path.
  CHECK(wait_for([&] {
    return status.Counter("/trainer", "frames_accepted") > accepted_before &&
           status.Counter("/camera", "frames_published") > published_before &&
           status.Value("/synthesizer", "model_version") >= 1.0 &&
           status.Value("/synthesizer", "model_version") > serving_before;
  }, 60s));
  CHECK(status.Counter("/trainer", "versions_published") >= 1);
  REQUIRE(client.Call(good_request, &reply, &error));
  INFO(reply.meta.error());
  REQUIRE(reply.meta.ok());
  REQUIRE(reply.meta.views_size() == 1);
  CHECK(reply.meta.views(0).model_version() >= 1);
  CHECK(reply.meta.views(0).method() == "p2i");
  REQUIRE(reply.images.size() == 2);
  CHECK(reply.images[0].width == 32);
  CHECK(reply.images[1].height == 32);
  // Topic mode -> sink and monitor.
  const uint64_t written_before = status.Counter("/slam_sink", "frames_written");
  const double monitor_before = status.Value("/monitor", "views");
  uint64_t request_id = 100;
  auto last_planned = Clock::now() - 1s;
  CHECK(wait_for([&] {
    if (Clock::now() - last_planned > 200ms) {
      last_planned = Clock::now();
      msgs::pb::PoseRequest r;
      r.set_request_id(++request_id);
      convert::ToMsg(sweep[request_id % sweep.size()].pose, r.mutable_pose());
      planned.Send(planned.Valid(r));
    }
    return status.Counter("/slam_sink", "frames_written") >= written_before + 3 &&
           status.Value("/monitor", "views") >= monitor_before + 3;
  }, 30s));

  // Every node is still alive and exits cleanly (any crash or failure would make this 1).
  CHECK(graph.Stop() == 0);
}

}  // namespace
}  // namespace p2i::pipeline
