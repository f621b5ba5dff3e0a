/// @file presets_test.cc
/// @brief Every shipped preset parses and validates; the ablation presets set the paper's switches;
/// unknown keys are errors naming key and file.
#include <filesystem>

#include <catch2/catch.hpp>

#include "model/p2i_config.h"
#include "tests/test_paths.h"

using p2i::model::P2iConfig;

TEST_CASE("every preset in model/presets parses and validates", "[unit]") {
  const auto dir = p2i::testing::SourceDir() + "/model/presets";
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() != ".yaml") continue;
    INFO(e.path());
    const auto c = P2iConfig::FromYamlFile(e.path().string());
    CHECK(c.name == e.path().stem().string());
    ++n;
  }
  CHECK(n >= 11);  // 8 ablation rows + cnn_baseline + default + default_256
  const auto row1 = P2iConfig::FromYamlFile(dir + "/ablation_row1_minimal.yaml");
  CHECK_FALSE(row1.depth);
  CHECK_FALSE(row1.attention);
  CHECK_FALSE(row1.hd);
  CHECK_FALSE(row1.ld);
  CHECK_FALSE(row1.enet);
  CHECK(row1.g_schedule == "fewer");
  const auto row8 = P2iConfig::FromYamlFile(dir + "/ablation_row8_full.yaml");
  CHECK(row8.depth);
  CHECK(row8.attention);
  CHECK(row8.hd);
  CHECK(row8.ld);
  CHECK(row8.enet);
  CHECK(row8.GeneratorWidths().back() == 1024);
  CHECK(P2iConfig::FromYamlFile(dir + "/cnn_baseline.yaml").IsBaseline());
  // The paper-literal presets keep every non-paper addition off.
  for (const std::string name : {"default", "default_256", "ablation_row1_minimal",
                                 "ablation_row8_full"}) {
    INFO(name);
    const auto p = P2iConfig::FromYamlFile(dir + "/" + name + ".yaml");
    CHECK(p.recon_weight == 0.0);
    CHECK(p.r1_gamma == 0.0);
    CHECK(p.pose_encoding == "none");
  }
  // The learning recipe is a new preset with its deviations on.
  const auto learn = P2iConfig::FromYamlFile(dir + "/learn_128.yaml");
  CHECK(learn.resolution == 128);
  CHECK(learn.recon_weight > 0.0);
}

TEST_CASE("config YAML: unknown keys and bad values are errors naming them", "[unit]") {
  CHECK_THROWS_WITH(P2iConfig::FromYamlString("resolutoin: 64\n", "x.yaml"),
                    Catch::Contains("unknown key 'resolutoin'") && Catch::Contains("x.yaml"));
  CHECK_THROWS_WITH(P2iConfig::FromYamlString("resolution: 100\n", "x.yaml"),
                    Catch::Contains("resolution"));
  CHECK_THROWS_WITH(P2iConfig::FromYamlString("resolution: 64\ng_widths: [8, 8]\n", "x.yaml"),
                    Catch::Contains("g_widths"));
  const auto c = P2iConfig::FromYamlString("resolution: 32\ng_widths: [8, 8, 8, 8]\nk1: 0.5\n", "x");
  const auto back = P2iConfig::FromYamlString(c.ToYamlString(), "round trip");
  CHECK(back.ToYamlString() == c.ToYamlString());
  CHECK(back.k1 == 0.5);
  CHECK_THROWS_WITH(P2iConfig::FromYamlString("pose_encoding: sine\n", "x.yaml"),
                    Catch::Contains("pose_encoding"));
  CHECK_THROWS_WITH(P2iConfig::FromYamlString("recon_weight: -1\n", "x.yaml"),
                    Catch::Contains("recon_weight"));
  const auto f = P2iConfig::FromYamlString(
      "resolution: 32\ng_widths: [8, 8, 8, 8]\npose_encoding: fourier\nfourier_bands: 3\n"
      "recon_weight: 10\nr1_gamma: 0.5\n", "x");
  const auto f2 = P2iConfig::FromYamlString(f.ToYamlString(), "round trip");
  CHECK(f2.PoseInputs() == 49);
  CHECK(f2.recon_weight == 10.0);
  CHECK(f2.r1_gamma == 0.5);
}

TEST_CASE("config --set overrides replace or add keys in order and name a bad one", "[unit]") {
  const auto demo = p2i::testing::SourceDir() + "/model/presets/demo_128.yaml";
  const auto plain = P2iConfig::FromYamlFile(demo);
  const auto same = P2iConfig::FromYamlFile(demo, {});
  CHECK(same.ToYamlString() == plain.ToYamlString());
  // densify_* are absent from the file (added), recon_weight is present (replaced), and a later
  // --set of the same key wins; g_widths takes a YAML list.
  const auto c = P2iConfig::FromYamlFile(
      demo, {"densify_ratio=3", "densify_method=warp", "recon_weight=200", "recon_weight=120",
             "g_widths=[64, 64, 32, 16, 8, 8]"});
  CHECK(plain.densify_ratio == 0.0);
  CHECK(c.densify_ratio == 3.0);
  CHECK(c.densify_method == "warp");
  CHECK(plain.recon_weight != 120.0);
  CHECK(c.recon_weight == 120.0);
  CHECK(c.g_widths == std::vector<int>{64, 64, 32, 16, 8, 8});
  CHECK(c.name == plain.name);
  CHECK(c.fourier_bands == plain.fourier_bands);
  CHECK_THROWS_WITH(P2iConfig::FromYamlFile(demo, {"densify_ratio"}),
                    Catch::Contains("--set 'densify_ratio'") && Catch::Contains("KEY=VALUE"));
  CHECK_THROWS_WITH(P2iConfig::FromYamlFile(demo, {"=3"}), Catch::Contains("KEY=VALUE"));
  CHECK_THROWS_WITH(P2iConfig::FromYamlFile(demo, {"densify_raito=3"}),
                    Catch::Contains("unknown key 'densify_raito'") &&
                        Catch::Contains("--set densify_raito=3") && Catch::Contains("demo_128.yaml"));
  CHECK_THROWS_WITH(P2iConfig::FromYamlFile(demo, {"densify_ratio=-1"}),
                    Catch::Contains("densify_ratio"));
  CHECK_THROWS_WITH(P2iConfig::FromYamlFile(demo, {"g_widths=[1, 2"}),
                    Catch::Contains("--set 'g_widths=[1, 2'") && Catch::Contains("not YAML"));
}
