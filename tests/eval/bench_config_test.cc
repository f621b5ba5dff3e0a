/// @file bench_config_test.cc
/// @brief The bench config: the shipped configs parse; bad ones stop at start-up naming the key
/// and the file.
#include <string>

#include <catch2/catch.hpp>

#include "eval/bench_config.h"
#include "tests/test_paths.h"

using namespace p2i::eval;

namespace {
const std::string kBase = R"(dataset: {scene: builtin:small_office, max_frames: 20}
settings: [a1, b]
period: 10
methods:
  - nearest
  - {name: p2i, preset: default, steps: 4, batch_size: 2, seeds: [1, 2, 3], max_train_s: 30,
     seed_sizes: [tiny]}
sizes:
  - {name: tiny, resolution: 32, model: {g_widths: [16, 16, 8, 8]}}
  - {name: small, resolution: 32, model: {g_widths: [32, 32, 16, 8]}}
)";

std::string ErrorOf(const std::string& text) {
  try {
    BenchConfig::FromYamlString(text, "my_bench.yaml");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("Bench configs: the shipped ones parse, defaults and overrides apply", "[unit]") {
  for (const char* name : {"tiny", "small_office_128", "large_office_128", "small_office_128_long", "ablation_64"}) {
    INFO(name);
    const auto c = BenchConfig::FromYamlFile(p2i::testing::SourceDir() + "/bench/configs/" + name + ".yaml");
    CHECK_FALSE(c.methods.empty());
    CHECK_FALSE(c.sizes.empty());
  }
  const BenchConfig c = BenchConfig::FromYamlString(kBase, "my_bench.yaml");
  REQUIRE(c.methods.size() == 2);
  CHECK(c.methods[0].type == "nearest");
  CHECK(c.methods[1].type == "p2i");
  CHECK(c.methods[1].max_train_s == Approx(30));
  CHECK(c.SeedsOf(c.methods[0]) == std::vector<int>{1});        // deterministic: one seed
  CHECK(c.SeedsOf(c.methods[1]) == std::vector<int>{1, 2, 3});  // per-method seeds
  const auto b = p2i::scene::EvalSetting::Parse("b");
  CHECK(c.RunsOf(c.methods[1], b, c.sizes[0]) == std::vector<int>{1, 2, 3});
  CHECK(c.RunsOf(c.methods[1], b, c.sizes[1]) == std::vector<int>{1});  // seed_sizes: [tiny]
  CHECK(c.RunsOf(c.methods[0], b, c.sizes[1]).empty());  // baseline: once per resolution
  const auto mc = c.ModelConfig(c.methods[1], c.sizes[1], 2);
  CHECK(mc.resolution == 32);
  CHECK(mc.g_widths == std::vector<int>{32, 32, 16, 8});
  CHECK(mc.steps_phase1 == 4);
  CHECK(mc.steps_phase2 == 1);  // default: steps / 4
  CHECK(mc.batch_size == 2);
  CHECK(mc.seed == 2);
  REQUIRE(c.settings.size() == 2);
  CHECK(c.settings[0].split == p2i::scene::SplitSetting::kMissingFrames);
  CHECK(c.settings[0].held_out == 1);
  CHECK(c.settings[1].split == p2i::scene::SplitSetting::kAdjacentTrajectory);
  CHECK(c.stability.setting.Name() == "a1");
  CHECK(c.auto_size.setting.Name() == "a1");
  CHECK(c.auto_size.method == "p2i");
  CHECK(c.auto_size.margin_db == Approx(0.5));
}

TEST_CASE("Bench config methods come from the registry: aliases, options, learned keys",
          "[unit]") {
  const BenchConfig c = BenchConfig::FromYamlString(R"(dataset: {scene: builtin:small_office}
settings: [c, a3]
methods:
  - {name: w, type: warp, k: 2, fill_holes: false, z_tolerance: 0.1}
  - {name: net, type: p2i_net, steps: 2}
  - {name: base, type: cnn_baseline}
sizes: [128]  # the default preset (g_widths) is for 128
)",
                                                    "my_bench.yaml");
  REQUIRE(c.methods.size() == 3);
  CHECK(c.methods[0].type == "warp");
  CHECK_FALSE(c.methods[0].IsLearned());
  CHECK(c.methods[0].options_yaml.find("z_tolerance") != std::string::npos);
  CHECK(c.methods[0].make);
  CHECK(c.methods[1].type == "p2i");  // alias resolved once, here
  CHECK(c.methods[1].IsLearned());
  CHECK(c.methods[2].type == "cnn");
  CHECK(c.methods[2].preset.find("cnn_baseline.yaml") != std::string::npos);  // default preset
  CHECK(c.ModelConfig(c.methods[2], c.sizes[0], 1).IsBaseline());
  CHECK(c.stability.setting.Name() == "c");  // the first setting as written
  // A learned-only key on a baseline, and a bad option value, stop at start-up.
  CHECK(ErrorOf("dataset: {scene: x}\nsettings: [a1]\nmethods: [{name: nearest, steps: 3}]\n"
                "sizes: [64]\n")
            .find("steps") != std::string::npos);
  CHECK(ErrorOf("dataset: {scene: x}\nsettings: [a1]\nmethods: [{name: warp, k: 0}]\n"
                "sizes: [64]\n")
            .find("my_bench.yaml") != std::string::npos);
  CHECK(ErrorOf("dataset: {scene: x}\nsettings: [a1]\nmethods: [{name: warp, k: 0}]\n"
                "sizes: [64]\n")
            .find("(method 'warp')") != std::string::npos);
  const std::string e =
      ErrorOf("dataset: {scene: x}\nsettings: [a1]\nmethods: [nerf]\nsizes: [64]\n");
  CHECK(e.find("p2i, cnn, nearest, warp") != std::string::npos);  // the registry's list
}

TEST_CASE("Bench config errors name the key and the file", "[unit]") {
  // Unknown top-level key.
  std::string e = ErrorOf(kBase + "treads: 2\n");
  CHECK(e.find("treads") != std::string::npos);
  CHECK(e.find("my_bench.yaml") != std::string::npos);
  // Unknown key inside a method.
  e = ErrorOf(R"(dataset: {scene: builtin:small_office}
settings: [a1]
methods: [{name: warp, kk: 3}]
sizes: [64]
)");
  CHECK(e.find("kk") != std::string::npos);
  CHECK(e.find("my_bench.yaml:3") != std::string::npos);
  // A P2iConfig override that does not exist: named with the file and the method.
  e = ErrorOf(R"(dataset: {scene: builtin:small_office}
settings: [a1]
methods: [{name: p2i, config: {widht: 3}}]
sizes: [64]
)");
  CHECK(e.find("widht") != std::string::npos);
  CHECK(e.find("my_bench.yaml") != std::string::npos);
  // Unknown setting, unknown method type, unknown preset, missing dataset, N >= period.
  CHECK(ErrorOf("dataset: {scene: x}\nsettings: [d]\nmethods: [nearest]\nsizes: [64]\n").find("'d'") != std::string::npos);
  CHECK(ErrorOf("dataset: {scene: x}\nsettings: [a1]\nmethods: [nerf]\nsizes: [64]\n").find("nerf") != std::string::npos);
  CHECK(ErrorOf("dataset: {scene: x}\nsettings: [a1]\nmethods: [{name: p, type: p2i, preset: nosuch}]\nsizes: [64]\n")
            .find("nosuch") != std::string::npos);
  CHECK(ErrorOf("settings: [a1]\nmethods: [nearest]\nsizes: [64]\n").find("dataset") != std::string::npos);
  CHECK(ErrorOf("dataset: {scene: x}\nsettings: [a20]\nperiod: 10\nmethods: [nearest]\nsizes: [64]\n")
            .find("period") != std::string::npos);
  CHECK(ErrorOf("dataset: {scene: x, path: y}\nsettings: [a1]\nmethods: [nearest]\nsizes: [64]\n")
            .find("exactly one") != std::string::npos);
  // dataset.sequences picks sequences of a folder: not of a sim scene, never an empty list.
  CHECK(ErrorOf("dataset: {scene: x, sequences: [seq-01]}\nsettings: [a1]\nmethods: [nearest]\nsizes: [64]\n")
            .find("dataset.sequences needs dataset.path") != std::string::npos);
  CHECK(ErrorOf("dataset: {path: y, sequences: []}\nsettings: [a1]\nmethods: [nearest]\nsizes: [64]\n")
            .find("non-empty list") != std::string::npos);
}

TEST_CASE("Bench config: the shipped sim configs render with the sensor model, exact on request",
          "[unit]") {
  for (const char* name :
       {"tiny", "small_office_128", "large_office_128", "small_office_128_long", "ablation_64"}) {
    INFO(name);
    const auto c = BenchConfig::FromYamlFile(p2i::testing::SourceDir() + "/bench/configs/" +
                                             name + ".yaml");
    CHECK(c.dataset.sensor.AnyNoise());
    CHECK(c.dataset.sensor.AnyColour());
    CHECK(c.dataset.sensor.MotionBlur());
    CHECK(c.dataset.specular);
  }
  // Without the keys: the exact render (no sensor effects), specular materials kept.
  const BenchConfig plain = BenchConfig::FromYamlString(kBase, "my_bench.yaml");
  CHECK_FALSE(plain.dataset.sensor.AnyEnabled());
  CHECK(plain.dataset.specular);
  const std::string exact = R"(dataset: {scene: builtin:large_office, sensor: {preset: none},
          specular: false}
settings: [a1]
methods: [nearest]
sizes: [64]
)";
  const BenchConfig e = BenchConfig::FromYamlString(exact, "my_bench.yaml");
  CHECK_FALSE(e.dataset.sensor.AnyEnabled());
  CHECK_FALSE(e.dataset.specular);
  const std::string bad = ErrorOf(R"(dataset: {scene: builtin:small_office,
  sensor: {preset: realistic, auto_exposure: 3}}
settings: [a1]
methods: [nearest]
sizes: [64]
)");
  CHECK(bad.find("my_bench.yaml:2") != std::string::npos);
  CHECK(bad.find("auto_exposure must be at most 1 (got 3)") != std::string::npos);
}

TEST_CASE("Bench config: a 4:3 size runs the methods that are not learned, learned ones skip it", "[unit]") {
  const std::string text = kBase + "  - {resolution: 40, height: 30}\n  - {name: c43, resolution: 32, height: 24}\n";
  const BenchConfig c = BenchConfig::FromYamlString(text, "my_bench.yaml");
  REQUIRE(c.sizes.size() == 4);
  CHECK(c.sizes[0].Square());
  CHECK(c.sizes[0].Height() == 32);
  CHECK(c.sizes[2].name == "r40x30");  // default name says both sides
  CHECK(c.sizes[2].Width() == 40);
  CHECK(c.sizes[2].Height() == 30);
  CHECK_FALSE(c.sizes[2].Square());
  const auto b = p2i::scene::EvalSetting::Parse("b");
  CHECK(c.RunsOf(c.methods[0], b, c.sizes[2]) == std::vector<int>{1});  // nearest at 40 x 30
  CHECK(c.RunsOf(c.methods[1], b, c.sizes[2]).empty());                 // p2i: square only
  // 32 x 24 is not 32 x 32: the baseline runs again at the new shape.
  CHECK(c.RunsOf(c.methods[0], b, c.sizes[3]) == std::vector<int>{1});
  CHECK(ErrorOf(kBase + "  - {resolution: 40, height: 8}\n").find("size height must be >= 16") !=
        std::string::npos);
}
