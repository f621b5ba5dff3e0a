/// @file pose_spacing_test.cc
/// @brief The training poses' spacing in the normalised input, the band count it calls for, and
/// `fourier_bands: auto` in the model config.
#include <cmath>
#include <stdexcept>
#include <string>

#include <catch2/catch.hpp>
#include <torch/torch.h>

#include "model/checkpoint.h"
#include "model/p2i_config.h"
#include "model/pose_spacing.h"
#include "tests/model/model_test_util.h"

using namespace p2i::model;

namespace {

// `n` inputs on a line along the first axis, `step` apart, unit quaternion (0, 0, 0, 1).
std::vector<std::array<float, 7>> Line(int n, float step) {
  std::vector<std::array<float, 7>> v;
  for (int i = 0; i < n; ++i) v.push_back({-1.0f + step * i, 0, 0, 0, 0, 0, 1});
  return v;
}

}  // namespace

TEST_CASE("the median neighbour distance of the training inputs", "[unit]") {
  CHECK(MedianNeighbourDistance(Line(10, 0.1f)) == Approx(0.1).epsilon(1e-5));
  // A gap in the line moves its two ends' neighbour distance, not the median.
  auto gapped = Line(9, 0.05f);
  gapped.push_back({1.5f, 0, 0, 0, 0, 0, 1});
  CHECK(MedianNeighbourDistance(gapped) == Approx(0.05).epsilon(1e-5));
  // Even count: the mean of the two middle distances (0.1, 0.1, 0.2, 0.2 -> 0.15).
  const std::vector<std::array<float, 7>> four{
      {0, 0, 0, 0, 0, 0, 1}, {0.1f, 0, 0, 0, 0, 0, 1}, {0.5f, 0, 0, 0, 0, 0, 1},
      {0.7f, 0, 0, 0, 0, 0, 1}};
  CHECK(MedianNeighbourDistance(four) == Approx(0.15).epsilon(1e-5));
  // The rotation part counts: two poses at one place, quaternions 0.2 apart.
  const std::vector<std::array<float, 7>> turned{{0, 0, 0, 0, 0, 0, 1}, {0, 0, 0, 0, 0, 0.2f, 1}};
  CHECK(MedianNeighbourDistance(turned) == Approx(0.2).epsilon(1e-5));
}

TEST_CASE("a pose captured twice is not its own neighbour, and one distinct pose has no spacing",
          "[unit]") {
  auto twice = Line(10, 0.1f);
  const auto again = Line(10, 0.1f);
  twice.insert(twice.end(), again.begin(), again.end());
  CHECK(MedianNeighbourDistance(twice) == Approx(0.1).epsilon(1e-5));
  const std::vector<std::array<float, 7>> same(5, {0.3f, 0, 0, 0, 0, 0, 1});
  CHECK(std::isnan(MedianNeighbourDistance(same)));
  CHECK(std::isnan(MedianNeighbourDistance({})));
  try {
    FourierBandsForSpacing(MedianNeighbourDistance(same));
    FAIL("no spacing gave a band count");
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    CHECK(what.find("fourier_bands") != std::string::npos);
    CHECK(what.find("set fourier_bands to a number") != std::string::npos);
  }
  CHECK_THROWS_AS(FourierBandsForSpacing(0.0), std::invalid_argument);
  CHECK_THROWS_AS(FourierBandsForSpacing(-0.1), std::invalid_argument);
}

TEST_CASE("the band count whose finest period is nearest the spacing", "[unit]") {
  // B bands end at period 2 / 2^(B - 1): a spacing equal to that period gives B.
  for (int b = 1; b <= 16; ++b) {
    INFO("bands " << b);
    CHECK(FourierBandsForSpacing(2.0 / std::pow(2.0, b - 1) / kAutoBandsPeriodRatio) == b);
  }
  // The measured spacings (docs/MODEL.md "Fourier band count"): the sim's densified a3 and b,
  // study-room a3 and a1 get the counts that scored best there.
  CHECK(FourierBandsForSpacing(0.0146) == 6);
  CHECK(FourierBandsForSpacing(0.0171) == 6);
  CHECK(FourierBandsForSpacing(0.0588) == 4);
  CHECK(FourierBandsForSpacing(0.0577) == 4);
  // Finer spacing, more bands (never fewer); clamped to the config's [1, 16].
  int last = 16;
  for (double s = 1e-6; s < 10; s *= 1.3) {
    const int b = FourierBandsForSpacing(s);
    CHECK(b <= last);
    CHECK(b >= 1);
    CHECK(b <= 16);
    last = b;
  }
  CHECK(FourierBandsForSpacing(1e-9) == 16);
  CHECK(FourierBandsForSpacing(100.0) == 1);
}

TEST_CASE("fourier_bands: auto parses, round-trips, and is refused where a count is needed",
          "[unit]") {
  const auto c = P2iConfig::FromYamlString(
      "resolution: 32\ng_widths: [8, 8, 8, 8]\npose_encoding: fourier\nfourier_bands: auto\n",
      "test");
  CHECK(c.fourier_bands == kAutoFourierBands);
  CHECK(c.AutoFourierBands());
  const std::string yaml = c.ToYamlString();
  CHECK(yaml.find("fourier_bands: auto") != std::string::npos);
  CHECK(P2iConfig::FromYamlString(yaml, "round trip").AutoFourierBands());
  // A count stays a count; auto without the Fourier encoding is not "still to choose".
  CHECK_FALSE(P2iConfig::FromYamlString("fourier_bands: 5\npose_encoding: fourier\n", "t")
                  .AutoFourierBands());
  const auto plain = P2iConfig::FromYamlString("fourier_bands: auto\npose_encoding: none\n", "t");
  CHECK_FALSE(plain.AutoFourierBands());
  CHECK(plain.PoseInputs() == 7);
  // While auto, G's input width is unknown: PoseInputs and the networks refuse.
  CHECK_THROWS_AS(c.PoseInputs(), std::logic_error);
  CHECK_THROWS_AS(Networks(c), std::logic_error);
  for (const char* bad : {"fourier_bands: lots\n", "fourier_bands: 0\n", "fourier_bands: 2.5\n",
                          "fourier_bands: 17\n"}) {
    INFO(bad);
    try {
      P2iConfig::FromYamlString(bad, "my.yaml");
      FAIL("accepted");
    } catch (const std::exception& e) {
      const std::string what = e.what();
      CHECK(what.find("fourier_bands") != std::string::npos);
    }
  }
}
