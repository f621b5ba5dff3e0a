/// @file results.h
/// @brief One row per (method, setting, size, seed) of `p2i bench`, and the crash-safe
/// results.csv / results.json writer (both rewritten atomically after every completed row).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace p2i::eval {

/// A per-view record kept in results.json (not in the CSV).
struct ViewRecord {
  std::string id;
  double psnr = 0.0;
  double ssim = 0.0;
  double lpips = 0.0;     ///< NaN = metric missing
  double coverage = 0.0;  ///< model::CoverageScorer score of the test pose
};

/// Every figure of one evaluated combination. NaN marks a missing value (written as "NA" in
/// the CSV and null in the JSON), never 0.
struct ResultRow {
  std::string method;       ///< the config's method name
  std::string method_type;  ///< nearest | warp | p2i | cnn
  std::string setting;      ///< a1 a3 a10 a20 b c
  std::string size;         ///< the config's size name
  int resolution = 0;       ///< view width
  int height = 0;           ///< view height (= resolution for square sizes; 0 read from old files)
  int seed = 0;
  int train_frames = 0;
  int test_views = 0;
  double psnr = 0.0, ssim = 0.0;
  double lpips = 0.0;  ///< LPIPS-Squeeze; NaN when the weights were not found
  double depth_abs_rel = 0.0, depth_rmse_m = 0.0, depth_valid_fraction = 0.0;
  double views_per_s = 0.0, latency_p50_ms = 0.0, latency_p99_ms = 0.0;
  int threads = 1;
  double train_s = 0.0;
  int train_steps_phase1 = 0, train_steps_phase2 = 0;
  double params = 0.0;          ///< parameters (0 for non-learned methods)
  double flops_per_view = 0.0;  ///< FLOPs per view, 2 x MACs (0 for non-learned methods)
  double coverage_spearman = 0.0;  ///< Spearman rho(coverage score, per-view PSNR)
  /// model/pose_dependence.h over the test views (1 = varies like the scene, 0 = collapsed)
  double pose_dependence = 0.0;
  std::vector<ViewRecord> views;

  /// "method|setting|size|seed": the identity used to resume.
  std::string Key() const;
};

/// The CSV header (one line, no newline) and one row (no newline).
std::string CsvHeader();
std::string CsvLine(const ResultRow& row);

/// results.csv + results.json in a folder. Add() appends a row and rewrites both files through
/// a temporary file + rename, so a killed run leaves every completed row readable and no partial
/// file. `config_hash` identifies the configuration the rows belong to (a resumed run must use
/// the same one). Not thread-safe.
class ResultsStore {
 public:
  ResultsStore(std::string dir, std::string config_hash);

  /// Reads DIR/results.json if it exists and belongs to the same config_hash; returns the number
  /// of rows loaded. Throws std::runtime_error naming the file when it holds rows of another
  /// configuration (use --fresh or another --out) or is malformed.
  size_t LoadExisting();
  bool Has(const std::string& key) const;
  void Add(ResultRow row);
  const std::vector<ResultRow>& rows() const { return rows_; }
  /// Writes both files now (also done by Add).
  void Flush() const;

  std::string csv_path() const;
  std::string json_path() const;

 private:
  std::string dir_;
  std::string config_hash_;
  std::vector<ResultRow> rows_;
};

/// Parses the text of a results.json (for tests and tools). Throws std::runtime_error.
std::vector<ResultRow> ParseResultsJson(const std::string& text, std::string* config_hash);
std::string ResultsToJson(const std::vector<ResultRow>& rows, const std::string& config_hash);

}  // namespace p2i::eval
