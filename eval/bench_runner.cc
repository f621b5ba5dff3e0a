/// @file bench_runner.cc
#include "eval/bench_runner.h"

#include <filesystem>

#include "eval/bench_stages.h"
#include "model/lpips.h"

namespace p2i::eval {
namespace fs = std::filesystem;

std::string FindLpipsWeights(const std::string& option) {
  const std::string resolved = model::LpipsSqueeze::ResolveWeightsPath(option);
  if (!resolved.empty()) return resolved;
  const fs::path shared =
      fs::path(P2I_EVAL_SHARED_DIR) / "models" / "lpips" / "lpips_squeeze_v0.1.pth";
  if (fs::exists(shared)) return shared.string();
  return "";
}

int RunBench(const BenchOptions& options) {
  BenchRun run = StartBench(options);
  RunMeasurements(run);
  ComposeStrips(run);
  WriteBenchCharts(run);
  AutoSizeStage(run);
  WriteBenchReport(run);
  return 0;
}

}  // namespace p2i::eval
