/// @file bench_stages_test.cc
/// @brief Stages of `p2i bench` run alone (eval/bench_stages.h): the auto-size choice over the
/// size ladder, the report from fixed rows, the stability pose set.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>

#include "eval/bench_stages.h"
#include "scene/trajectory.h"
#include "tests/read_file.h"
#include "tests/temp_dir.h"

using namespace p2i::eval;
namespace fs = std::filesystem;

namespace {

const std::string kLadder = R"(dataset: {scene: builtin:small_office, max_frames: 20}
settings: [b, a1]
period: 10
methods:
  - nearest
  - {name: p2i, preset: default, steps: 4, batch_size: 2, max_train_s: 30}
sizes:
  - {name: tiny, resolution: 32, model: {g_widths: [16, 16, 8, 8]}}
  - {name: small, resolution: 32, model: {g_widths: [32, 32, 16, 8]}}
)";

ResultRow Row(const std::string& method, const std::string& setting, const std::string& size,
              int seed, double psnr, double params) {
  ResultRow r;
  r.method = method;
  r.method_type = method;
  r.setting = setting;
  r.size = size;
  r.resolution = 32;
  r.seed = seed;
  r.test_views = 3;
  r.psnr = psnr;
  r.ssim = 0.5;
  r.lpips = std::nan("");
  r.params = params;
  r.flops_per_view = params * 10;
  r.views_per_s = 1e7 / (params + 1);
  return r;
}

// p2i on the auto-size setting (b, the first of the config): tiny 20.0 / 20.2 dB over two seeds,
// small 20.5 dB with four times the parameters; a1 rows that must not count.
std::vector<ResultRow> LadderRows() {
  return {Row("p2i", "b", "tiny", 1, 20.0, 1e5), Row("p2i", "b", "tiny", 2, 20.2, 1e5),
          Row("p2i", "b", "small", 1, 20.5, 4e5), Row("p2i", "a1", "tiny", 1, 10.0, 1e5),
          Row("p2i", "a1", "small", 1, 30.0, 4e5), Row("nearest", "b", "tiny", 1, 25.0, 0)};
}

}  // namespace

TEST_CASE("bench auto-size stage: the smallest size within the margin of the best", "[unit]") {
  const BenchConfig c = BenchConfig::FromYamlString(kLadder, "ladder.yaml");
  REQUIRE(c.auto_size.method == "p2i");
  REQUIRE(c.auto_size.setting.Name() == "b");

  // Mean over seeds: tiny 20.1, small 20.5: tiny is within 0.5 dB, not within 0.3 dB.
  auto ladder = ChooseOnLadder(c, LadderRows(), 0.5);
  REQUIRE(ladder);
  REQUIRE(ladder->candidates.size() == 2);
  CHECK(ladder->candidates[0].name == "tiny");
  CHECK(ladder->candidates[0].psnr_db == Approx(20.1));
  CHECK(ladder->candidates[1].psnr_db == Approx(20.5));
  CHECK(ladder->candidates[1].params == Approx(4e5));
  CHECK(ladder->choice.index == 0);
  CHECK(ladder->choice.best_index == 1);
  CHECK(ladder->markdown.find("Ladder of `p2i` on setting b (margin 0.50 dB PSNR)") !=
        std::string::npos);
  CHECK(ladder->markdown.find("| **tiny** | 20.10 | 0.100 M | 0.001 |") != std::string::npos);
  CHECK(ladder->markdown.find("| small | 20.50 |") != std::string::npos);
  CHECK(ladder->markdown.find("\n--auto-size: " + ladder->choice.reason) != std::string::npos);

  ladder = ChooseOnLadder(c, LadderRows(), 0.3);
  REQUIRE(ladder);
  CHECK(ladder->choice.index == 1);
  CHECK(ladder->markdown.find("| **small** | 20.50 |") != std::string::npos);

  // One size: nothing to choose.
  std::string one = kLadder.substr(0, kLadder.find("  - {name: small"));
  CHECK_FALSE(ChooseOnLadder(BenchConfig::FromYamlString(one, "one.yaml"), LadderRows(), 0.5));

  // The stage: the paragraph for the report and OUT/auto_size.txt.
  p2i::testing::TempDir dir("bench_stages_auto");
  BenchRun run(BenchOptions{}, c, dir.path());
  run.margin_db = 0.5;
  for (const auto& r : LadderRows()) run.store.Add(r);
  AutoSizeStage(run);
  REQUIRE(run.auto_size.size() == 1);
  CHECK(run.auto_size[0] == ChooseOnLadder(c, LadderRows(), 0.5)->markdown);
  CHECK(p2i::testing::ReadFile(dir / "auto_size.txt") ==
        ChooseOnLadder(c, LadderRows(), 0.5)->choice.reason + "\n");
}

TEST_CASE("bench auto-size stage across methods: the cheapest method within the margin",
          "[unit]") {
  std::string text = kLadder;
  text.replace(text.find("  - nearest\n"), 12, "  - nearest\n  - warp\n");
  text += "auto_size: {setting: b, methods: [nearest, warp, p2i]}\n";
  const BenchConfig c = BenchConfig::FromYamlString(text, "across.yaml");
  REQUIRE(c.auto_size.methods == std::vector<std::string>{"nearest", "warp", "p2i"});
  std::vector<ResultRow> rows = LadderRows();
  ResultRow warp = Row("warp", "b", "tiny", 1, 25.0, 0);
  warp.views_per_s = 400;
  rows.push_back(warp);  // nearest b tiny: 25.0 dB too in LadderRows, at 1e7 views/s

  // At tiny: nearest, warp (both 25.0 dB, no parameters) and p2i (20.1). At small only p2i ran.
  std::vector<LadderChoice> across = ChooseAcrossMethods(c, rows, 0.5);
  REQUIRE(across.size() == 1);
  REQUIRE(across[0].candidates.size() == 3);
  CHECK(across[0].size == "tiny");
  CHECK(across[0].candidates[across[0].choice.index].name == "nearest");  // faster at equal PSNR
  CHECK(across[0].markdown.find("Across methods at size `tiny` (32x32) on setting b") !=
        std::string::npos);
  CHECK(across[0].markdown.find("| **nearest** | 25.00 |") != std::string::npos);
  CHECK(across[0].choice.reason.find("of the methods within") != std::string::npos);
  rows[5].psnr = 24.0;  // nearest now 1 dB below warp: outside 0.5 dB
  across = ChooseAcrossMethods(c, rows, 0.5);
  CHECK(across[0].candidates[across[0].choice.index].name == "warp");
  CHECK(across[0].choice.reason.find("cheaper methods fall outside the margin: 'nearest'") !=
        std::string::npos);

  // The stage writes the size ladder's paragraph and this one.
  p2i::testing::TempDir dir("bench_stages_across");
  BenchRun run(BenchOptions{}, c, dir.path());
  run.margin_db = 0.5;
  for (const auto& r : rows) run.store.Add(r);
  AutoSizeStage(run);
  REQUIRE(run.auto_size.size() == 2);
  CHECK(run.auto_size[1] == across[0].markdown);
  CHECK(p2i::testing::ReadFile(dir / "auto_size.txt") ==
        ChooseOnLadder(c, rows, 0.5)->choice.reason + "\n" + across[0].choice.reason + "\n");

  // Refusals name the key.
  std::string bad = kLadder + "auto_size: {methods: [nearest, gan]}\n";
  CHECK_THROWS_WITH(BenchConfig::FromYamlString(bad, "bad.yaml"),
                    Catch::Contains("auto_size.methods: 'gan' is not in methods"));
  bad = kLadder + "auto_size: {methods: [nearest]}\n";
  CHECK_THROWS_WITH(BenchConfig::FromYamlString(bad, "bad.yaml"),
                    Catch::Contains("at least two"));
}

TEST_CASE("bench report stage: report.md from fixed rows, without a measurement", "[unit]") {
  p2i::testing::TempDir dir("bench_stages_report");
  BenchOptions o;
  o.config_path = "ladder.yaml";
  o.quiet = true;
  BenchRun run(o, BenchConfig::FromYamlString(kLadder, "ladder.yaml"), dir.path());
  run.threads = 3;
  run.lpips_status = "missing (test)";
  for (const auto& r : LadderRows()) run.store.Add(r);

  const ReportInputs ri = MakeReportInputs(run);
  CHECK(ri.command == "p2i bench ladder.yaml");
  CHECK(ri.dataset == "(report rebuilt from results.json)");
  CHECK(ri.machine.find("3 LibTorch thread(s) for learned methods") != std::string::npos);
  CHECK(ri.lpips_status == "missing (test)");
  // One note per learned method: its training budget at the first size and seed.
  REQUIRE(ri.notes.size() == 1);
  CHECK(ri.notes[0].rfind("`p2i` trained 4 phase-1 steps", 0) == 0);
  CHECK(ri.notes[0].find(" at batch 2 (the paper: tens of thousands)") != std::string::npos);
  CHECK(ri.notes[0].find("each run capped at 30 s") != std::string::npos);

  // The report's tables come from the chart inputs (the charts stage runs before it).
  run.chart_inputs = MakeChartInputs(run.config, run.store.rows(), run.stability);
  CHECK(run.chart_inputs.settings == std::vector<std::string>{"a1", "b"});  // the paper's order
  run.dataset = "sim scene `x`";
  WriteBenchReport(run);
  const std::string md = p2i::testing::ReadFile(dir / "report.md");
  CHECK(md.find("| data | sim scene `x` |") != std::string::npos);
  CHECK(md.find("| p2i | b | small | 1 | 20.50 |") != std::string::npos);
  CHECK(md.find("| nearest | b | tiny | 1 | 25.00 |") != std::string::npos);
  CHECK(md.find(ri.notes[0]) != std::string::npos);
}

TEST_CASE("bench stability stage: the perturbed pose set", "[unit]") {
  const auto sim = p2i::scene::SimScene::FromSpec("builtin:small_office");
  const auto camera = p2i::scene::SimScene::DefaultCamera(16, 12);
  p2i::scene::AdjacentSweepsOptions sweeps;
  sweeps.count = 1;
  std::vector<p2i::scene::Pose> train;
  const auto trajectories = p2i::scene::GenerateAdjacentSweeps(sweeps);
  for (const auto& s : trajectories.at(0)) train.push_back(s.pose);
  REQUIRE(train.size() > 10);
  StabilitySpec spec;
  spec.poses = 3;
  spec.translations_m = {0.0, 0.1, 0.3};
  spec.rotations_deg = {0.0, 10.0};

  const auto samples = MakeStabilitySamples(spec, sim, camera, train);
  // Per base pose (first, middle, last training pose): the translations, then the rotations.
  REQUIRE(samples.size() == 3 * 5);
  const size_t bases[] = {0, (train.size() - 1) / 2, train.size() - 1};
  for (int b = 0; b < 3; ++b) {
    const p2i::scene::Pose& base = train[bases[b]];
    for (int k = 0; k < 5; ++k) {
      const StabilitySample& s = samples[b * 5 + k];
      INFO("base " << b << " sample " << k);
      if (k < 3) {
        CHECK(s.kind == "translation");
        CHECK(s.offset == spec.translations_m[k]);
        CHECK((s.pose.translation() - base.translation()).norm() == Approx(s.offset).margin(1e-9));
        CHECK(s.pose.rotation().angularDistance(base.rotation()) == Approx(0).margin(1e-9));
        CHECK(sim.IsFree(s.pose.translation(), s.offset == 0.0 ? 0.0 : 0.1));
      } else {
        CHECK(s.kind == "rotation");
        CHECK(s.offset == spec.rotations_deg[k - 3]);
        CHECK((s.pose.translation() - base.translation()).norm() == 0.0);
        CHECK(s.pose.rotation().angularDistance(base.rotation()) * 180 / M_PI ==
              Approx(s.offset).margin(1e-6));
      }
      // The exact ground truth at the perturbed pose, and its distance to the training poses.
      CHECK(s.gt.rgb.cols == 16);
      CHECK(s.gt.rgb.rows == 12);
      CHECK(cv::norm(s.gt.rgb, sim.Render(s.pose, camera).rgb, cv::NORM_INF) == 0);
      if (s.offset == 0.0) CHECK(s.nearest == Approx(0).margin(1e-9));
      if (s.offset > 0.0) CHECK(s.nearest > 0.0);
    }
  }
  // Seeded: the same set every time (every method is swept on the same poses).
  const auto again = MakeStabilitySamples(spec, sim, camera, train);
  REQUIRE(again.size() == samples.size());
  for (size_t i = 0; i < samples.size(); ++i) CHECK(again[i].pose.equals(samples[i].pose, 1e-12));
}
