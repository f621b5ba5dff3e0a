/// @file ws_protocol_test.cc
/// @brief foxglove.websocket.v1 messages: server JSON, client request parsing (bad input never
/// throws), the binary message-data frame.
#include <catch2/catch.hpp>

#include <cstring>

#include <nlohmann/json.hpp>

#include "nodes/foxglove_bridge/ws_protocol.h"

using namespace p2i::foxglove_bridge;

TEST_CASE("Foxglove protocol: server messages have the spec's fields", "[unit]") {
  const auto info = nlohmann::json::parse(ServerInfoJson("p2i_foxglove_bridge", "42"));
  CHECK(info["op"] == "serverInfo");
  CHECK(info["name"] == "p2i_foxglove_bridge");
  CHECK(info["capabilities"].is_array());
  CHECK(info["sessionId"] == "42");
  ChannelInfo c{7, "/rgbd", "protobuf", "p2i.msgs.pb.RgbdFrame", std::string("\x01\x02\xff", 3), "/rgbd"};
  const auto adv = nlohmann::json::parse(AdvertiseJson({c}));
  CHECK(adv["op"] == "advertise");
  REQUIRE(adv["channels"].size() == 1);
  CHECK(adv["channels"][0]["id"] == 7);
  CHECK(adv["channels"][0]["topic"] == "/rgbd");
  CHECK(adv["channels"][0]["encoding"] == "protobuf");
  CHECK(adv["channels"][0]["schemaName"] == "p2i.msgs.pb.RgbdFrame");
  CHECK(adv["channels"][0]["schema"] == "AQL/");  // base64
  CHECK(nlohmann::json::parse(UnadvertiseJson({1, 2}))["channelIds"].size() == 2);
  CHECK(nlohmann::json::parse(StatusJson(2, "x"))["level"] == 2);
  CHECK(Base64("") == "");
  CHECK(Base64("f") == "Zg==");
  CHECK(Base64("fo") == "Zm8=");
  CHECK(Base64("foo") == "Zm9v");
}

TEST_CASE("Foxglove protocol: client requests parse, bad ones get a reason", "[unit]") {
  auto r = ParseClientText(R"({"op":"subscribe","subscriptions":[{"id":0,"channelId":3},{"id":1,"channelId":4}]})");
  REQUIRE(r.kind == ClientRequest::kSubscribe);
  REQUIRE(r.subscriptions.size() == 2);
  CHECK(r.subscriptions[1] == std::make_pair(1u, 4u));
  r = ParseClientText(R"({"op":"unsubscribe","subscriptionIds":[0,1]})");
  REQUIRE(r.kind == ClientRequest::kUnsubscribe);
  CHECK(r.unsubscribe_ids.size() == 2);
  CHECK(ParseClientText(R"({"op":"advertise","channels":[]})").kind == ClientRequest::kUnsupported);
  for (const char* bad :
       {"", "{", "[]", "null", "42", R"({"op":1})", R"({"nop":"subscribe"})",
        R"({"op":"subscribe"})", R"({"op":"subscribe","subscriptions":{}})",
        R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":3}]})",
        R"({"op":"subscribe","subscriptions":[{"id":1}]})",
        R"({"op":"subscribe","subscriptions":[{"id":4294967296,"channelId":3}]})",
        R"({"op":"subscribe","subscriptions":[7]})", R"({"op":"unsubscribe","subscriptionIds":["a"]})",
        "\xff\xfe\x00garbage"}) {
    INFO(bad);
    const auto b = ParseClientText(bad);
    CHECK(b.kind == ClientRequest::kBad);
    CHECK_FALSE(b.error.empty());
  }
}

TEST_CASE("Foxglove protocol: message data frame layout", "[unit]") {
  const std::string f = MessageDataFrame(0x01020304u, 0x1122334455667788ull, "abc");
  REQUIRE(f.size() == 16);
  CHECK(static_cast<uint8_t>(f[0]) == 0x01);
  uint32_t sub = 0;
  uint64_t ts = 0;
  std::memcpy(&sub, f.data() + 1, 4);
  std::memcpy(&ts, f.data() + 5, 8);
  CHECK(sub == 0x01020304u);
  CHECK(ts == 0x1122334455667788ull);
  CHECK(f.substr(13) == "abc");
}
