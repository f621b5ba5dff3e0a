/// @file bench_stages.h
/// @brief The stages of `p2i bench`, in the order RunBench (bench_runner.h) runs them: start
/// (output folder, resume, LPIPS), measurements (per setting x size x method x seed: training,
/// evaluation, strip views, stability sweep), strips, charts, auto-size, report. A BenchRun
/// carries what one stage leaves for the next; each stage is declared here so that a test can
/// run it alone. Not thread-safe.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "eval/bench_config.h"
#include "eval/bench_runner.h"
#include "eval/charts.h"
#include "eval/report.h"
#include "eval/results.h"
#include "eval/stats.h"
#include "model/lpips.h"
#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"
#include "scene/sim_scene.h"

namespace p2i::eval {

/// The state of one `p2i bench` run, filled stage by stage.
struct BenchRun {
  BenchRun(BenchOptions options, BenchConfig config, std::string out_dir);

  const BenchOptions options;
  const BenchConfig config;
  const std::string out_dir;
  int threads = 1;                  ///< LibTorch threads of learned methods (option, else config)
  double margin_db = 0.5;           ///< auto-size margin (option, else config)
  std::string started, load_start;  ///< UTC time and load average at the start
  ResultsStore store;               ///< the rows (resumed ones first)
  std::vector<StabilityPoint> stability;
  std::unique_ptr<model::LpipsSqueeze> lpips;  ///< null: LPIPS reported as missing
  std::string lpips_status;
  /// One line describing the data; empty when the rows come from results.json (--report-only).
  std::string dataset;
  std::vector<std::pair<std::string, std::string>> strips;  ///< (setting, strips/NAME.png)
  ChartInputs chart_inputs;
  ChartOutputs charts;
  std::vector<std::string> auto_size;  ///< the ladder paragraph, when auto-size ran
};

/// Start: reads the config, makes the output folder (removing earlier results with --fresh),
/// loads the rows and stability points of an earlier run, finds the LPIPS weights. Throws on a
/// bad config or a results.json of another config.
BenchRun StartBench(const BenchOptions& options);

/// Training and evaluation: renders or reads the data, makes every setting's split (a setting
/// the data cannot run fails before the first row), then for each setting x size x method x
/// seed trains (learned methods) or builds the method, evaluates the test views into a row,
/// renders the strip views and runs the stability sweep, skipping what an earlier run did. With
/// --report-only it only checks that results.json exists.
void RunMeasurements(BenchRun& run);

/// Strips: one PNG per setting from the saved strip views (run.strips).
void ComposeStrips(BenchRun& run);

/// Charts: the chart inputs of the rows (settings in the paper's order) and the gnuplot charts
/// in OUT/charts (run.chart_inputs, run.charts).
ChartInputs MakeChartInputs(const BenchConfig& config, const std::vector<ResultRow>& rows,
                            const std::vector<StabilityPoint>& stability);
void WriteBenchCharts(BenchRun& run);

/// Auto-size: the choice over the size ladder of the config's auto-size method on its setting,
/// from the rows. Empty when the config has one size or no auto-size method.
struct LadderChoice {
  std::vector<SizeCandidate> candidates;  ///< one per size, config order
  AutoSizeChoice choice;
  std::string markdown;  ///< the report's ladder table and the choice
  std::string size;      ///< across methods: the size the candidates ran at
};
std::optional<LadderChoice> ChooseOnLadder(const BenchConfig& config,
                                           const std::vector<ResultRow>& rows, double margin_db);
/// Across methods (config auto_size.methods): at each size where at least two of the methods
/// were measured on the auto-size setting, the cheapest within the margin of their best
/// (ChooseAutoSize with noun "method"). One LadderChoice per such size, config order.
std::vector<LadderChoice> ChooseAcrossMethods(const BenchConfig& config,
                                              const std::vector<ResultRow>& rows, double margin_db);
/// Runs ChooseOnLadder and ChooseAcrossMethods on the run's rows: run.auto_size, OUT/auto_size.txt,
/// and the printed choices with --auto-size.
void AutoSizeStage(BenchRun& run);

/// Report: the report's inputs from the run (command, data, machine, LPIPS, charts, strips,
/// ladder, the training budget of each learned method), then OUT/report.md.
ReportInputs MakeReportInputs(const BenchRun& run);
void WriteBenchReport(const BenchRun& run);

/// One perturbed pose of the stability sweep with its exact ground truth.
struct StabilitySample {
  std::string kind;  ///< "translation" (offset in m) or "rotation" (offset in deg)
  double offset;
  scene::Pose pose;
  scene::RgbdSample gt;
  double nearest;  ///< model::CoverageScorer::NearestDistance to the training poses
};

/// Stability pose set: from `spec.poses` training poses (evenly spaced), each translation
/// offset in a random direction (a free point of the sim, 50 attempts, else skipped) and each
/// rotation offset about a random axis; seeded, so every run and method gets the same set.
std::vector<StabilitySample> MakeStabilitySamples(const StabilitySpec& spec,
                                                  const scene::SimScene& sim,
                                                  const scene::CameraInfo& camera,
                                                  const std::vector<scene::Pose>& train);

}  // namespace p2i::eval
