/// @file option_error_test.cc
/// @brief The one shape of a refused node option (nodes/runtime/option_error.h).
#include <stdexcept>
#include <string>

#include <catch2/catch.hpp>

#include "nodes/runtime/option_error.h"

using p2i::runtime::CheckOption;
using p2i::runtime::CheckSizePair;

namespace {
template <class F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("CheckOption: NODE: NAME must RULE (got VALUE) - FIX, values shown by type", "[unit]") {
  CHECK(ErrorOf([] { CheckOption(true, "n", "rate", 0.0, "be > 0", "e.g. rate:=1"); }).empty());
  CHECK(ErrorOf([] { CheckOption(false, "n", "rate", 0.05, "be > 1", "e.g. rate:=2"); }) ==
        "n: rate must be > 1 (got 0.05); e.g. rate:=2");
  CHECK(ErrorOf([] { CheckOption(false, "n", "mode", std::string("x"), "be a", "mode:=a"); }) ==
        "n: mode must be a (got 'x'); mode:=a");
  CHECK(ErrorOf([] { CheckOption(false, "n", "check", true, "be false", "check:=false"); }) ==
        "n: check must be false (got true); check:=false");
}

TEST_CASE("CheckSizePair: width and height both > 0 or both 0", "[unit]") {
  for (const auto& [w, h] : {std::pair{0, 0}, std::pair{320, 240}, std::pair{1, 1}})
    CHECK(ErrorOf([w = w, h = h] { CheckSizePair("camera", w, h, "fix"); }).empty());
  CHECK(ErrorOf([] { CheckSizePair("camera", 320, 0, "set both or neither"); }) ==
        "camera: width and height must both be > 0 or both 0 (got 320x0); set both or neither");
  CHECK(ErrorOf([] { CheckSizePair("synthesizer", 0, 64, "fix"); }) ==
        "synthesizer: width and height must both be > 0 or both 0 (got 0x64); fix");
}
