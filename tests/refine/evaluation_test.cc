/// @file evaluation_test.cc
/// @brief `p2i refine eval`'s figures (refine/evaluation.h): the plain fusion blend is scored as
/// the fusion method serves it, with the pixels no surface covers filled, not left black.
#include "refine/evaluation.h"

#include <catch2/catch.hpp>

#include "tests/fusion/fusion_test_util.h"

using namespace p2i;
using fusion::testing::At;
using fusion::testing::Cam;
using fusion::testing::PlaneScene;

TEST_CASE("refine eval: the fusion blend's holes are filled as the fusion method fills them", "[unit]") {
  const PlaneScene scene;
  const auto cam = Cam(64, 48, 60);
  scene::RgbdDataset train, test;
  train.camera = test.camera = cam;
  for (double x : {-0.1, 0.0, 0.1}) train.frames.push_back(scene.Render(At(x, 0, 0), cam));
  // 0.7 m to the side: the view's far edge sees plane no training frame saw (a hole, ~1/4).
  test.frames.push_back(scene.Render(At(0.7, 0.0, 0.0), cam));
  refine::SplitEvalOptions o;
  o.width = 64;
  o.height = 48;
  o.fuse_width = 0;  // fuse the frames as given
  o.finetune.steps = 0;
  o.scratch = false;
  const refine::SplitEvalReport r = refine::EvaluateSplit(train, test, "", o);
  const refine::MethodScore* blend = nullptr;
  for (const auto& m : r.methods)
    if (m.method == "fusion_blend") blend = &m;
  REQUIRE(blend != nullptr);
  REQUIRE(blend->views == 1);
  // The hole is there ...
  CHECK(blend->observed > 0.5);
  CHECK(blend->observed < 0.9);
  // ... and filled: left black, a third of the view scores 10.5 dB; push-pull filled (the smooth
  // texture's mean colour spreads into the hole) 18.3 dB.
  CHECK(blend->psnr > 14.0);
}
