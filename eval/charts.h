/// @file charts.h
/// @brief gnuplot charts of `p2i bench`: data files + .gp scripts always, PNG and SVG when
/// gnuplot is installed (otherwise the scripts are left for later and the run goes on).
#pragma once

#include <string>
#include <vector>

#include "eval/results.h"

namespace p2i::eval {

/// One stability sample: mean quality of a method at one offset from the training poses.
struct StabilityPoint {
  std::string method;
  std::string kind;  ///< "translation" (m) or "rotation" (deg)
  double offset = 0.0;
  double psnr = 0.0;    ///< mean over the sampled poses
  double ssim = 0.0;
  double nearest_distance = 0.0;  ///< mean CombinedPoseDistance to the nearest training pose
  int n = 0;
};

struct ChartInputs {
  std::vector<ResultRow> rows;
  std::vector<std::string> settings;  ///< config order
  std::vector<std::string> methods;   ///< config order
  std::vector<std::string> sizes;     ///< config order
  std::string primary_setting;        ///< the setting of the speed/accuracy charts
  std::vector<StabilityPoint> stability;
  double threshold_db = 20.0;
};

/// What was produced: chart names (file stems in dir) and a note for the report.
struct ChartOutputs {
  std::vector<std::string> charts;  ///< stems with .png/.svg (or only .gp when no gnuplot)
  bool gnuplot_ran = false;
  std::string note;
};

/// Writes DIR/<chart>.dat and DIR/<chart>.gp and, if gnuplot is found (`gnuplot_command`, default
/// "gnuplot", looked up on PATH), runs it to make <chart>.png and <chart>.svg.
ChartOutputs WriteCharts(const ChartInputs& in, const std::string& dir,
                         const std::string& gnuplot_command = "gnuplot");

/// Mean over seeds of the rows of (method, setting, size); NaN when none. `field` is one of
/// psnr, ssim, lpips, views_per_s, params, flops.
double MeanOver(const std::vector<ResultRow>& rows, const std::string& method,
                const std::string& setting, const std::string& size, const std::string& field);

}  // namespace p2i::eval
