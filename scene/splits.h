/// @file splits.h
/// @brief Train/test splits for the paper's three settings, deterministic and saved to a file.
#pragma once

#include <string>
#include <vector>

#include "scene/dataset_index.h"

namespace p2i::scene {

/// The three evaluation settings of the P2I-NET paper.
enum class SplitSetting {
  kMissingFrames,       ///< (a) held-out frames within trajectories
  kAdjacentTrajectory,  ///< (b) train on one whole trajectory, test on an adjacent one
  kCrossTrajectory,     ///< (c) train on several trajectories, test on others
};

std::string ToString(SplitSetting setting);  ///< "missing_frames", "adjacent_trajectory", ...
/// Throws std::invalid_argument listing the valid names.
SplitSetting SplitSettingFromString(const std::string& name);

/// A setting as `p2i bench` configs and result tables name it: "a1", "a3", "a10", "a20" (setting
/// (a) with N frames of every period held out), "b" (adjacent trajectory), "c" (cross
/// trajectory). Parsed once, where a config is read; code compares values, not strings.
/// A value type.
struct EvalSetting {
  SplitSetting split = SplitSetting::kMissingFrames;
  int held_out = 1;  ///< (a): N frames held out per period; 0 for (b) and (c)

  std::string Name() const;  ///< "a3", "b", "c"
  /// Throws std::invalid_argument naming `name` and listing the six names.
  static EvalSetting Parse(const std::string& name);
  /// The paper's order: a1 < a3 < a10 < a20 < b < c.
  bool operator<(const EvalSetting& other) const;
  bool operator==(const EvalSetting& other) const;
  bool operator!=(const EvalSetting& other) const { return !(*this == other); }
};

/// The six settings of the paper's tables, in its order.
const std::vector<EvalSetting>& PaperSettings();

/// Frame ids for training and testing plus the setting and its parameters. A value type.
struct Split {
  SplitSetting setting = SplitSetting::kMissingFrames;
  // (a) parameters.
  int period = 100;   ///< frames per block
  int held_out = 0;   ///< N: frames held out after each full block
  // (a): the sequences the rule was applied to; (b), (c): the train / test trajectories.
  std::vector<std::string> train_sequences;
  std::vector<std::string> test_sequences;
  std::vector<std::string> train;  ///< frame ids, dataset order
  std::vector<std::string> test;   ///< frame ids, dataset order

  /// Throws std::invalid_argument when train is empty, an id repeats, or train and test overlap.
  void Validate() const;

  std::string ToYamlString() const;
  void ToYamlFile(const std::string& path) const;  ///< atomic (temp + rename)
  /// Unknown keys, a bad setting name or a failing Validate() are errors naming `source`.
  static Split FromYamlString(const std::string& text, const std::string& source = "<string>");
  static Split FromYamlFile(const std::string& path);

  bool operator==(const Split& other) const;
};

/// Setting (a), the paper's rule in 0-based positions: frame i (of `count`, in time order) is
/// held out iff i >= period, i % period < N, and its block is complete, i.e.
/// (i / period) * period + N <= count. With period 100 and N = 3 the held-out positions are
/// 100, 101, 102, 200, 201, 202, ... (the paper's 1-based frames 100m+1 ... 100m+N, m >= 1,
/// 100M + N <= total). Returns a mask, true = test. Throws std::invalid_argument unless
/// 0 < N < period.
std::vector<bool> MissingFramesMask(size_t count, int held_out, int period = 100);

/// Setting (a) applied to each of `sequences` separately (empty = every sequence); frames of
/// other sequences are in neither list.
Split MakeMissingFramesSplit(const DatasetIndex& dataset, int held_out, int period = 100,
                             const std::vector<std::string>& sequences = {});
/// Setting (b): every frame of train_sequence for training, every frame of test_sequence for
/// testing. Throws std::invalid_argument for an unknown or identical sequence.
Split MakeAdjacentTrajectorySplit(const DatasetIndex& dataset, const std::string& train_sequence,
                                  const std::string& test_sequence);
/// Setting (c): whole trajectories; the two lists must be non-empty and disjoint.
Split MakeCrossTrajectorySplit(const DatasetIndex& dataset,
                               const std::vector<std::string>& train_sequences,
                               const std::vector<std::string>& test_sequences);

}  // namespace p2i::scene
