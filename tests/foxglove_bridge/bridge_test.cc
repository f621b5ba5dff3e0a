/// @file bridge_test.cc
/// @brief BridgeNode in-process against hand-rolled WebSocket clients (so the test controls
/// every byte): subprotocol check, serverInfo + advertise, subscribe -> binary frames that
/// decode, bad requests answered and counted, a client that never reads gets drops while
/// another keeps receiving, unsubscribe.
#include <catch2/catch.hpp>


#include <atomic>
#include <cstring>
#include <thread>

#include <nlohmann/json.hpp>

#include "convert/pose.h"
#include "msgs/codec.h"
#include "nodes/foxglove_bridge/bridge_node.h"
#include "nodes/runtime/shutdown.h"
#include "recording/inline_blobs.h"
#include "tests/foxglove_bridge/raw_ws_client.h"
#include "tests/runtime/test_util.h"

using namespace p2i;
using nlohmann::json;
using p2i::testing::RawWs;

namespace {

uint32_t ChannelOf(const json& advertise, const std::string& topic) {
  for (const auto& c : advertise["channels"])
    if (c["topic"] == topic) return c["id"].get<uint32_t>();
  return 0;
}

}  // namespace

// long-function: one scenario on one bridge: each step (subscribe, bad requests, slow client,
// unsubscribe) starts from the state the previous one left
TEST_CASE("p2i_foxglove_bridge: advertise, subscribe, bad requests, slow client, unsubscribe",
          "[integration]") {
  runtime::Shutdown::ResetForTesting();
  runtime::testing::ScopedRunDir run_dir;
  runtime::Node camera("camera", runtime::NodeArgs::Parse(std::vector<std::string>{}));
  auto pub = camera.Advertise<msgs::RgbdFrame>("rgbd");
  foxglove_bridge::BridgeNode bridge(runtime::NodeArgs::Parse(std::vector<std::string>{
      "port:=0", "max_queue_mb:=1", "discovery_period:=0.1", "status_period:=0"}));
  std::atomic<bool> stop{false};
  bridge.Start();
  std::thread spin([&] {
    while (!stop) bridge.SpinOnce(std::chrono::milliseconds(5));
  });
  const int port = bridge.Port();
  REQUIRE(port > 0);
  std::atomic<int> published{0};
  std::thread publisher([&] {
    msgs::RgbdFrame f;
    f.meta.set_camera_info_id("cam");
    convert::SetPose({0, 0, 1, 0, 0, 0, 1}, f.meta.mutable_pose());
    f.rgb = msgs::Image::Allocate(msgs::pb::RGB8, 320, 240);
    f.depth = msgs::Image::Allocate(msgs::pb::DEPTH32F, 320, 240);
    while (!stop) {
      pub->Publish(f);
      ++published;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  });

  {  // No foxglove subprotocol: refused.
    RawWs no(port);
    REQUIRE(no.ok());
    CHECK(no.Handshake("").find(" 101 ") == std::string::npos);
  }
  RawWs a(port);
  REQUIRE(a.ok());
  const std::string head = a.Handshake("foxglove.websocket.v1");
  REQUIRE(head.find(" 101 ") != std::string::npos);
  CHECK(head.find("foxglove.websocket.v1") != std::string::npos);
  const json info = a.WaitText([](const json& j) { return j["op"] == "serverInfo"; });
  CHECK(info["name"] == "p2i_foxglove_bridge");
  const json adv = a.WaitText([](const json& j) {
    return j["op"] == "advertise" && ChannelOf(j, "/rgbd") != 0;
  });
  const uint32_t rgbd = ChannelOf(adv, "/rgbd");
  REQUIRE(rgbd != 0);
  CHECK(ChannelOf(adv, "/rgbd/foxglove/rgb") != 0);
  for (const auto& c : adv["channels"]) {
    if (c["id"] == rgbd) CHECK(c["schemaName"] == "p2i.msgs.pb.RgbdFrame");
  }

  // Bad requests: each answered with an error status, counted, connection kept.
  a.SendFrame(1, "{not json");
  a.SendFrame(2, "\x01\x02\x03");
  a.SendFrame(1, R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":999999}]})");
  a.SendFrame(1, R"({"op":"unsubscribe","subscriptionIds":[77]})");
  int errors = 0;
  for (int i = 0; i < 4; ++i)
    errors += !a.WaitText([](const json& j) { return j["op"] == "status" && j["level"] == 2; }).is_null();
  CHECK(errors == 4);
  CHECK(bridge.ServerStats().bad_requests.load() >= 4);

  // Subscribe: binary frames [0x01][sub id][timestamp][RgbdFrame with inline pixels].
  a.SendFrame(1, json{{"op", "subscribe"}, {"subscriptions", {{{"id", 5}, {"channelId", rgbd}}}}}.dump());
  int frames = 0;
  uint8_t op;
  std::string p;
  for (int i = 0; i < 200 && frames < 3 && a.ReadFrame(&op, &p); ++i) {
    if (op != 2) continue;
    REQUIRE(p.size() > 13);
    CHECK(static_cast<uint8_t>(p[0]) == 0x01);
    uint32_t sub = 0;
    std::memcpy(&sub, p.data() + 1, 4);
    CHECK(sub == 5);
    msgs::WireMessage w;
    std::string error;
    REQUIRE(recording::ExtractBlobs("p2i.msgs.pb.RgbdFrame",
                                    reinterpret_cast<const uint8_t*>(p.data()) + 13, p.size() - 13,
                                    &w, &error));
    msgs::RgbdFrame f;
    REQUIRE(msgs::Decode(w, &f, &error));
    CHECK(f.rgb.width == 320);
    ++frames;
  }
  CHECK(frames == 3);

  // A client that subscribes and never reads: its queue fills, messages to it are dropped
  // (counted) while client a keeps receiving.
  RawWs slow(port);
  slow.ShrinkReceiveBuffer();
  REQUIRE(slow.Handshake("foxglove.websocket.v1").find(" 101 ") != std::string::npos);
  slow.SendFrame(1, json{{"op", "subscribe"}, {"subscriptions", {{{"id", 1}, {"channelId", rgbd}}}}}.dump());
  int later = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < deadline &&
         (bridge.ServerStats().dropped.load() == 0 || later < 20)) {
    if (a.ReadFrame(&op, &p, 1000) && op == 2) ++later;
  }
  CHECK(bridge.ServerStats().dropped.load() > 0);
  CHECK(later >= 20);
  CHECK(bridge.ServerStats().clients.load() == 2);

  // Unsubscribe: after what was in flight, nothing more on subscription 5.
  a.SendFrame(1, R"({"op":"unsubscribe","subscriptionIds":[5]})");
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  while (a.ReadFrame(&op, &p, 200)) {
  }
  int after = 0;
  const auto quiet = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
  while (std::chrono::steady_clock::now() < quiet)
    if (a.ReadFrame(&op, &p, 100) && op == 2) ++after;
  CHECK(after == 0);

  stop = true;
  publisher.join();
  spin.join();
}
