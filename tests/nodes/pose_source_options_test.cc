/// @file pose_source_options_test.cc
/// @brief PoseSourceOptions: the declared defaults are the struct's, parameters override them,
/// every Validate() rule refuses a bad value naming the parameter and showing the value.
#include "nodes/pose_source/pose_source_options.h"

#include <catch2/catch.hpp>

#include "tests/option_test_util.h"

namespace p2i::nodes {
namespace {

using namespace p2i::testing;

TEST_CASE("PoseSourceOptions: declared defaults are the field initialisers", "[unit]") {
  const runtime::Parameters p = CheckDefaults<PoseSourceOptions>(10);
  const PoseSourceOptions d;
  CHECK(p.Declared().at("trajectory").default_text == d.trajectory);
  CHECK(p.Declared().at("frame_id").default_text == d.frame_id);
  CHECK(p.Declared().at("rate").default_text == "20");
  CHECK(d.PlannedRate() == d.rate);  // planned_rate 0 = rate

  const PoseSourceOptions s =
      OptionsFrom<PoseSourceOptions>({{"planned_rate", "5"}, {"trajectory", "orbit"}});
  CHECK(s.PlannedRate() == 5.0);
  CHECK(s.trajectory == "orbit");
}

TEST_CASE("PoseSourceOptions::Validate refuses each bad value, naming parameter and value",
          "[unit]") {
  CheckRefusals<PoseSourceOptions>(
      "pose_source",
      {
          {{{"trajectory", "''"}}, "trajectory must name a trajectory spec (got '')"},
          {{{"trajectory_index", "-1"}}, "trajectory_index must be >= 0 (got -1)"},
          {{{"planned_trajectory_index", "-3"}},
           "planned_trajectory_index must be >= 0 (got -3)"},
          {{{"rate", "0"}}, "rate must be > 0 (got 0)"},
          {{{"planned_rate", "-2.5"}}, "planned_rate must be >= 0 (got -2.5)"},
      });
}

}  // namespace
}  // namespace p2i::nodes
