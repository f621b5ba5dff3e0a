/// @file slam_sink_options_test.cc
/// @brief SlamSinkNodeOptions: the node's declared defaults are the struct's (the sink's own
/// defaults, out_dir "slam_sequence"), parameters override them, Validate() is the sink's.
#include "nodes/slam_sink/slam_sink_options.h"

#include <catch2/catch.hpp>

#include "tests/option_test_util.h"

namespace p2i::slam_sink {
namespace {

using namespace p2i::testing;

TEST_CASE("SlamSinkNodeOptions: declared defaults are the field initialisers", "[unit]") {
  const runtime::Parameters p = CheckDefaults<SlamSinkNodeOptions>(22);
  const SlamSinkNodeOptions d;
  const SlamSinkOptions sink;
  CHECK(d.sink.writer.out_dir == "slam_sequence");
  CHECK(p.Declared().at("out_dir").default_text == "slam_sequence");
  CHECK(p.Declared().at("policy").default_text == sink.policy);
  CHECK(p.Declared().at("odometry_method").default_text == sink.checker.method);
  CHECK(p.Declared().at("png_compression").default_text ==
        std::to_string(sink.writer.png_compression));
  CHECK(p.Declared().at("views_topic").default_text == "views");
  CHECK(p.Declared().at("camera_info_topic").default_text == "camera_info");
  CHECK(p.Declared().at("summary_period").default_text == "5");

  const SlamSinkNodeOptions s = OptionsFrom<SlamSinkNodeOptions>(
      {{"out_dir", "/tmp/seq"}, {"policy", "drop"}, {"min_coverage", "0.25"},
       {"real_topic", "frames"}, {"summary_period", "0"}});
  CHECK(s.sink.writer.out_dir == "/tmp/seq");
  CHECK(s.sink.policy == "drop");
  CHECK(s.sink.checker.min_coverage == 0.25);
  CHECK(s.real_topic == "frames");
  CHECK(s.summary_period == 0.0);
  CHECK_NOTHROW(s.Validate());
}

TEST_CASE("SlamSinkNodeOptions::Validate refuses a bad value, naming parameter and value",
          "[unit]") {
  CheckRefusals<SlamSinkNodeOptions>(
      "slam_sink", {{{{"policy", "keep"}}, "policy must be flag or drop (got 'keep')"}});
}

}  // namespace
}  // namespace p2i::slam_sink
