/// @file monitor_options_test.cc
/// @brief MonitorOptions: the declared defaults are the struct's, parameters override them,
/// every Validate() rule refuses a bad value naming the parameter and showing the value.
#include "nodes/monitor/monitor_options.h"

#include <catch2/catch.hpp>

#include "tests/option_test_util.h"

namespace p2i::nodes {
namespace {

using namespace p2i::testing;

TEST_CASE("MonitorOptions: declared defaults are the field initialisers", "[unit]") {
  const runtime::Parameters p = CheckDefaults<MonitorOptions>(9);
  CHECK(p.Declared().at("duration").default_text == "120");
  CHECK(p.Declared().at("scene").default_text == MonitorOptions().scene);
  CHECK(p.Declared().at("camera_width").default_text == "640");

  const MonitorOptions s =
      OptionsFrom<MonitorOptions>({{"duration", "0"}, {"score_every", "4"}});
  CHECK(s.duration == 0.0);
  CHECK(s.score_every == 4);
  CHECK_NOTHROW(s.Validate());
}

TEST_CASE("MonitorOptions::Validate refuses each bad value, naming parameter and value",
          "[unit]") {
  CheckRefusals<MonitorOptions>(
      "monitor", {
                     {{{"duration", "-1"}}, "duration must be >= 0 (got -1)"},
                     {{{"camera_width", "0"}}, "camera_width must be > 0 (got 0)"},
                     {{{"camera_height", "-480"}}, "camera_height must be > 0 (got -480)"},
                     {{{"score_every", "0"}}, "score_every must be >= 1 (got 0)"},
                 });
}

}  // namespace
}  // namespace p2i::nodes
