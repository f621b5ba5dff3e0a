/// @file bench_runner.h
/// @brief `p2i bench`: for each setting x size x method x seed, train (learned methods), render
/// the test poses, measure quality and speed, write rows as they complete, then stability,
/// charts and the report. See docs/EVALUATION.md.
#pragma once

#include <string>

namespace p2i::eval {

struct BenchOptions {
  std::string config_path;
  std::string out_dir;          ///< default: bench_out/<config file stem>
  bool fresh = false;           ///< discard earlier results in out_dir instead of resuming
  std::string lpips_weights;    ///< overrides the config's (then P2I_LPIPS_WEIGHTS, ../shared)
  int threads = -1;             ///< overrides the config's
  bool auto_size = false;       ///< print the --auto-size choice
  double auto_size_margin_db = -1.0;  ///< overrides the config's (default 0.5 dB)
  bool report_only = false;     ///< rebuild charts and report from out_dir/results.json
  bool quiet = false;
  std::string command_line;     ///< for the report ("p2i bench ...")
};

/// Runs the benchmark; returns the process exit code (0 on success). Throws on bad config
/// (naming key and file) and on I/O errors.
int RunBench(const BenchOptions& options);

/// The LPIPS weights path that would be used: option, else $P2I_LPIPS_WEIGHTS, else
/// ../shared/models/lpips/lpips_squeeze_v0.1.pth beside the checkout if it exists, else "".
std::string FindLpipsWeights(const std::string& option);

}  // namespace p2i::eval
