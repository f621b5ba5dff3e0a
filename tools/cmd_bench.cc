/// @file cmd_bench.cc
/// @brief `p2i bench CONFIG.yaml [--out DIR]`: methods x settings x sizes x seeds on a dataset,
/// results.csv/json, charts, report (eval/bench_runner.h, docs/EVALUATION.md).
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "eval/bench_runner.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

int RunBenchCommand(const std::vector<std::string>& args) {
  CLI::App app{"Benchmark synthesis methods (nearest, warp, P2I-NET, CNN baseline, ablation rows) "
               "on the paper's settings: quality (PSNR, SSIM, LPIPS-Squeeze, depth), speed, "
               "stability, model size. Writes results.csv/json, charts and report.md.",
               "p2i bench"};
  eval::BenchOptions o;
  app.add_option("config", o.config_path, "bench config YAML (e.g. bench/configs/tiny.yaml)")
      ->required();
  app.add_option("--out", o.out_dir, "output folder (default bench_out/<config name>)");
  app.add_flag("--fresh", o.fresh, "discard earlier results in the output folder (default: resume)");
  app.add_option("--lpips-weights", o.lpips_weights,
                 "LPIPS-Squeeze weights (default: config, $P2I_LPIPS_WEIGHTS, ../shared)");
  app.add_option("--threads", o.threads, "LibTorch threads (overrides the config)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--auto-size", o.auto_size,
               "print the smallest size within the margin of the ladder's best PSNR, and why");
  app.add_option("--auto-size-margin", o.auto_size_margin_db, "dB PSNR (default: config, 0.5)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--report-only", o.report_only, "rebuild charts and report from results.json");
  app.add_flag("--quiet", o.quiet, "no progress output");
  std::vector<std::string> rev(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rev);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  o.command_line = "p2i";
  for (const auto& a : args) o.command_line += " " + a;
  return eval::RunBench(o);
}

P2I_COMMAND("bench", "Benchmark methods x settings x sizes: results, charts, report", RunBenchCommand);

}  // namespace
}  // namespace p2i::tools
