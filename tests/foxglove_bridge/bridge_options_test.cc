/// @file bridge_options_test.cc
/// @brief BridgeOptions: the declared defaults are the struct's, parameters override them, every
/// Validate() rule refuses a bad value naming the parameter and showing the value.
#include "nodes/foxglove_bridge/bridge_options.h"

#include <catch2/catch.hpp>

#include "tests/option_test_util.h"

namespace p2i::foxglove_bridge {
namespace {

using namespace p2i::testing;

TEST_CASE("BridgeOptions: declared defaults are the field initialisers", "[unit]") {
  const runtime::Parameters p = CheckDefaults<BridgeOptions>(7);
  const BridgeOptions d;
  CHECK(d.Server().max_queue_bytes == d.server.max_queue_bytes);  // 16 MiB, as max_queue_mb
  CHECK(p.Declared().at("port").default_text == std::to_string(d.server.port));
  CHECK(p.Declared().at("max_queue_mb").default_text == "16");
  CHECK(p.Declared().at("address").default_text == d.server.address);

  const BridgeOptions s = OptionsFrom<BridgeOptions>(
      {{"max_queue_mb", "1"}, {"topics", "[rgbd, views]"}, {"port", "0"}});
  CHECK(s.Server().max_queue_bytes == (1u << 20));
  CHECK(s.topics == std::vector<std::string>{"rgbd", "views"});
  CHECK_NOTHROW(s.Validate());
}

TEST_CASE("BridgeOptions::Validate refuses each bad value, naming parameter and value",
          "[unit]") {
  CheckRefusals<BridgeOptions>(
      "foxglove_bridge",
      {
          {{{"address", "''"}}, "address must name a listen address (got '')"},
          {{{"port", "70000"}}, "port must be in [0, 65535] (got 70000)"},
          {{{"port", "-1"}}, "port must be in [0, 65535] (got -1)"},
          {{{"max_queue_mb", "0"}}, "max_queue_mb must be at least 1 KiB (0.0009765625) (got 0)"},
          {{{"max_queue_mb", "-4"}}, "max_queue_mb must be at least 1 KiB (0.0009765625) (got -4)"},
          {{{"discovery_period", "0"}}, "discovery_period must be > 0 (got 0)"},
      });
}

}  // namespace
}  // namespace p2i::foxglove_bridge
