/// @file report.h
/// @brief The Markdown report of `p2i bench` (OUT/report.md): run description, the results
/// table, seed spread, coverage correlation, charts, stability, size ladder and image strips.
#pragma once

#include <string>
#include <vector>

#include "eval/charts.h"
#include "eval/results.h"

namespace p2i::eval {

struct ReportInputs {
  std::string title = "p2i bench report";
  std::string command;       ///< the command line that produced it
  std::string config_path;
  std::string dataset;       ///< one line describing the data
  std::string machine;       ///< cores, load averages, threads
  std::string started, finished;
  std::string lpips_status;  ///< "weights: PATH" or the reason it is missing
  ChartInputs chart_inputs;
  ChartOutputs charts;       ///< produced in OUT/charts
  std::vector<std::pair<std::string, std::string>> strips;  ///< (setting, relative PNG path)
  std::vector<std::string> auto_size;  ///< one paragraph per auto-sized method
  std::vector<std::string> notes;      ///< free text (e.g. training budget warnings)
};

/// The Markdown text (links relative to the output folder).
std::string RenderReportMarkdown(const ReportInputs& in);

/// "falls below X dB at D" lines per method and kind from the stability points.
std::vector<std::string> StabilitySummary(const std::vector<StabilityPoint>& points,
                                          const std::vector<std::string>& methods,
                                          double threshold_db);

}  // namespace p2i::eval
