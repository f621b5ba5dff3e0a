/// @file camera_options_test.cc
/// @brief CameraOptions: the declared defaults are the struct's, only the selected backend's
/// parameters are declared, and every Validate() rule refuses a bad value naming the parameter
/// and showing the value.
#include "nodes/camera/camera_options.h"

#include <string>

#include <catch2/catch.hpp>

#include "tests/option_test_util.h"

namespace p2i::nodes {
namespace {

using namespace p2i::testing;
using runtime::Parameters;

TEST_CASE("CameraOptions: declared defaults are the field initialisers, per backend", "[unit]") {
  const CameraOptions d;
  Parameters sim;
  const CameraOptions s = CameraOptions::FromParameters(sim);
  CHECK(s.backend == "sim");
  CHECK(sim.Declared().at("rate").default_text == "20");
  CHECK(sim.Declared().at("scene").default_text == d.sim.scene);
  CHECK(sim.Declared().at("loop").default_text == "true");
  CHECK(sim.Declared().count("dataset") == 0);  // replay's: refused as unknown with sim
  CHECK(sim.Declared().count("pose_tolerance") == 0);
  CheckAllDefaultsDescribed(sim);
  CHECK_NOTHROW(s.Validate());

  Parameters replay;
  replay.SetOverride("backend", "replay");
  CameraOptions r = CameraOptions::FromParameters(replay);
  CHECK(replay.Declared().at("rate").default_text == "0");  // the recorded stamps
  CHECK(replay.Declared().at("loop").default_text == "false");
  CHECK(replay.Declared().count("scene") == 0);
  CHECK(r.replay.rate == d.replay.rate);

  for (const char* backend : {"aravis", "libcamera"}) {
    INFO(backend);
    Parameters live;
    live.SetOverride("backend", backend);
    live.SetOverride("width", "320");
    const CameraOptions l = CameraOptions::FromParameters(live);
    const bool aravis = std::string(backend) == "aravis";
    // The stream size and buffers are the selected device's; their defaults live_backend.h's.
    CHECK(live.Declared().at("buffers").default_text ==
          std::to_string(aravis ? AravisOptions().buffers : LibcameraOptions().buffers));
    CHECK((aravis ? l.live.aravis.width : l.live.libcamera.width) == 320);
    CHECK(live.Declared().count("device") == (aravis ? 1u : 0u));
    CHECK(live.Declared().count("camera") == (aravis ? 0u : 1u));
    CHECK(YAML::Load(live.Declared().at("pose_tolerance").default_text).as<double>() ==
          LiveSourceOptions().pose_tolerance);
    CHECK_NOTHROW(l.Validate());
  }
}

TEST_CASE("CameraOptions::Validate refuses each bad value, naming parameter and value",
          "[unit]") {
  CheckRefusals<CameraOptions>("camera", {
      {{{"backend", "gige"}}, "backend must be sim, replay, aravis or libcamera (got 'gige')"},
      {{{"rate", "0"}}, "rate must be > 0 (got 0)"},
      {{{"width", "-1"}}, "width must be in [0, 8192] (got -1)"},
      {{{"height", "9000"}}, "height must be in [0, 8192] (got 9000)"},
      {{{"pose_mode", "none"}}, "pose_mode must be topic or trajectory (got 'none')"},
      {{{"trajectory_index", "-2"}}, "trajectory_index must be >= 0 (got -2)"},
      {{{"backend", "replay"}}, "dataset must name a dataset folder for backend replay (got '')"},
      {{{"backend", "replay"}, {"dataset", "d"}, {"rate", "-1"}}, "rate must be >= 0 (got -1)"},
      {{{"backend", "replay"}, {"dataset", "d"}, {"rate_scale", "0"}},
       "rate_scale must be > 0 (got 0)"},
      {{{"backend", "replay"}, {"dataset", "d"}, {"width", "320"}},
       "width and height must both be > 0 or both 0 (got 320x0); set both (centre-crop + "
       "resize) or neither (native size)"},
      {{{"backend", "replay"}, {"dataset", "d"}, {"width", "9000"}, {"height", "10"}},
       "width must be in [0, 8192] (got 9000)"},
      {{{"backend", "aravis"}, {"width", "-5"}}, "width must be in [0, 8192] (got -5)"},
      {{{"backend", "libcamera"}, {"height", "8193"}}, "height must be in [0, 8192] (got 8193)"},
      {{{"backend", "aravis"}, {"pose_mode", "trajectory"}},
       "pose_mode must be topic or none (got 'trajectory')"},
      {{{"backend", "aravis"}, {"pose_tolerance", "-0.5"}},
       "pose_tolerance must be >= 0 (got -0.5)"},
      {{{"backend", "libcamera"}, {"pose_wait", "-1"}}, "pose_wait must be >= 0 (got -1)"},
      {{{"backend", "aravis"}, {"max_pending", "0"}}, "max_pending must be >= 1 (got 0)"},
      {{{"backend", "aravis"}, {"buffers", "1"}}, "buffers must be >= 2 (got 1)"},
      {{{"backend", "aravis"}, {"depth_scale", "0"}}, "depth_scale must be > 0 (got 0)"},
      {{{"backend", "libcamera"}, {"buffers", "1"}}, "buffers must be >= 2 (got 1)"},
  });
  // The good neighbours of the refused values pass.
  CHECK(ValidationError<CameraOptions>({{"backend", "replay"}, {"dataset", "d"}, {"width", "320"}, {"height", "240"}})
            .empty());
  CHECK(ValidationError<CameraOptions>({{"backend", "aravis"}, {"pose_mode", "none"}, {"max_pending", "1"}}).empty());
  CHECK(ValidationError<CameraOptions>({{"backend", "aravis"}, {"buffers", "2"}, {"depth_scale", "1e-4"}}).empty());
  CHECK(ValidationError<CameraOptions>({{"pose_mode", "trajectory"}, {"width", "8192"}}).empty());
}

}  // namespace
}  // namespace p2i::nodes
