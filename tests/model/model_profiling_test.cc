/// @file model_profiling_test.cc
/// @brief ProfileTrainingStep (bench/model_bench.cc --profile) on the tiny config: the step's
/// eight sections in order then the two measured apart, finite times, a total of the eight.
#include "model/model_profiling.h"

#include <cmath>

#include <catch2/catch.hpp>

#include "tests/model/model_test_util.h"

using namespace p2i::model;
using namespace p2i::model::testing;

TEST_CASE("ProfileTrainingStep: the sections of one adversarial step, then attention and SN apart",
          "[unit]") {
  const StepProfile p = ProfileTrainingStep(TinyConfig(), /*steps=*/2, /*threads=*/1);
  const std::vector<std::string> names = {"G forward",        "D fwd reals",
                                          "D fwd fakes (D)",  "L_D + D backward",
                                          "D Adam",           "D fwd fakes (G)",
                                          "L_G + G backward", "G Adam"};
  REQUIRE(p.sections.size() == names.size() + 2);
  double sum = 0.0;
  for (size_t k = 0; k < p.sections.size(); ++k) {
    INFO(p.sections[k].first);
    if (k < names.size()) {
      CHECK(p.sections[k].first == names[k]);
      sum += p.sections[k].second;
    }
    CHECK(std::isfinite(p.sections[k].second));
    CHECK(p.sections[k].second >= 0.0);
  }
  CHECK(p.sections[8].first.rfind("(apart) attention", 0) == 0);
  CHECK(p.sections[9].first.rfind("(apart) SN power iterations", 0) == 0);
  CHECK(p.total == Approx(sum));
  CHECK(p.total > 0.0);
  // The baseline has no discriminator: nothing to profile.
  CHECK(ProfileTrainingStep(TinyConfig("cnn_baseline"), 1, 1).sections.empty());
}
