/// @file sim_scenes_test.cc
/// @brief The randomised sim scenes of the cross-scene refinement: deterministic, and their
/// materials and lights differ from the base scene and from each other.
#include <catch2/catch.hpp>

#include "refine/sim_scenes.h"

using namespace p2i;

TEST_CASE("Randomised sim scenes are deterministic and differ from the base", "[unit]") {
  const scene::SimScene base = scene::SimScene::BuiltIn("small_office");
  const scene::SimScene a = refine::MakeSimVariant("small_office", 1, 7);
  const scene::SimScene b = refine::MakeSimVariant("small_office", 1, 7);
  const scene::SimScene c = refine::MakeSimVariant("small_office", 2, 7);
  CHECK(a.description().materials[0].color == b.description().materials[0].color);
  CHECK(a.description().materials[0].color != base.description().materials[0].color);
  CHECK(a.description().materials[0].color != c.description().materials[0].color);
  CHECK(a.description().lights[0].intensity != base.description().lights[0].intensity);
  CHECK(a.sensor_options().AnyEnabled());  // index 1: sensor model on

  refine::SimScenesOptions o;
  o.scenes = 2;
  o.frames = 3;
  o.width = 32;
  o.height = 24;
  const auto scenes = refine::MakeSimScenes(o);
  REQUIRE(scenes.size() == 2);
  CHECK(scenes[0].name == "small_office_v0");
  CHECK(scenes[1].name == "large_office_v1");
  REQUIRE(scenes[0].frames.frames.size() == 3);
  CHECK(scenes[0].frames.frames[0].rgb.cols == 32);
  CHECK(cv::countNonZero(scenes[0].frames.frames[0].depth > 0) > 32 * 24 / 2);
  o.frames = 1;
  CHECK_THROWS_AS(refine::MakeSimScenes(o), std::invalid_argument);
}
