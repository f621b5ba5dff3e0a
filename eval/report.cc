/// @file report.cc
#include "eval/report.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "eval/stats.h"
#include "model/pose_dependence.h"

namespace p2i::eval {
namespace {

std::string F(double v, const char* fmt = "%.2f") {
  if (!std::isfinite(v)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof(buf), fmt, v);
  return buf;
}

}  // namespace

std::vector<std::string> StabilitySummary(const std::vector<StabilityPoint>& points,
                                          const std::vector<std::string>& methods,
                                          double threshold_db) {
  std::vector<std::string> out;
  for (const auto& m : methods) {
    std::string line;
    for (const std::string kind : {"translation", "rotation"}) {
      std::vector<double> d, q;
      for (const auto& p : points)
        if (p.method == m && p.kind == kind) {
          d.push_back(p.offset);
          q.push_back(p.psnr);
        }
      if (d.empty()) continue;
      const double at = FirstDistanceBelow(d, q, threshold_db);
      const std::string unit = kind == "translation" ? " m" : " deg";
      std::string part;
      if (std::isnan(at))
        part = "stays above " + F(threshold_db, "%.1f") + " dB up to " + F(d.back(), "%.3g") + unit +
               " of " + kind;
      else if (at == d.front())
        part = "is below " + F(threshold_db, "%.1f") + " dB already at " + F(at, "%.3g") + unit +
               " of " + kind + " (" + F(q.front()) + " dB)";
      else
        part = "falls below " + F(threshold_db, "%.1f") + " dB at " + F(at, "%.3g") + unit + " of " +
               kind;
      line += (line.empty() ? "" : "; ") + part;
    }
    if (!line.empty()) out.push_back("**" + m + "** " + line + ".");
  }
  return out;
}

namespace {

void WriteHeader(const ReportInputs& in, std::ostringstream& md) {
  md << "# " << in.title << "\n\n";
  md << "| | |\n|---|---|\n";
  md << "| command | `" << in.command << "` |\n";
  md << "| config | `" << in.config_path << "` |\n";
  md << "| data | " << in.dataset << " |\n";
  md << "| machine | " << in.machine << " |\n";
  md << "| run | " << in.started << " to " << in.finished << " (UTC) |\n";
  md << "| LPIPS-Squeeze | " << in.lpips_status << " |\n\n";
  for (const auto& n : in.notes) md << "> " << n << "\n\n";
}

void WriteResultsTable(const std::vector<ResultRow>& rows, std::ostringstream& md) {
  md << "## Results (one row per method, setting, size, seed)\n\n"
     << "PSNR/SSIM on RGB in [0, 1]; LPIPS-Squeeze (SqueezeNet backbone, not comparable with "
        "LPIPS-Alex); depth AbsRel / RMSE over pixels valid in both, `valid` = predicted share of "
        "the measurable depth; speed at batch 1 with the stated threads; rho = Spearman "
        "correlation of the coverage score with the per-view PSNR; pose-dep = pose-dependence "
        "(per-pixel std of the views over the test poses / that of the ground truth; below 0.5 "
        "the method collapsed to one image, docs/EVALUATION.md). Full figures: "
        "[results.csv](results.csv), [results.json](results.json).\n\n";
  md << "| method | setting | size | seed | PSNR dB | SSIM | LPIPS-Sq | AbsRel | RMSE m | valid | "
        "views/s | p50 ms | p99 ms | thr | train s | steps | params | GFLOP/view | rho | pose-dep |\n";
  md << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : rows) {
    md << "| " << r.method << " | " << r.setting << " | " << r.size << " | " << r.seed << " | "
       << F(r.psnr) << " | " << F(r.ssim, "%.3f") << " | " << F(r.lpips, "%.3f") << " | "
       << F(r.depth_abs_rel, "%.3f") << " | " << F(r.depth_rmse_m, "%.3f") << " | "
       << F(r.depth_valid_fraction, "%.2f") << " | " << F(r.views_per_s, "%.1f") << " | "
       << F(r.latency_p50_ms, "%.1f") << " | " << F(r.latency_p99_ms, "%.1f") << " | " << r.threads
       << " | " << F(r.train_s, "%.1f") << " | "
       << (r.train_steps_phase1 + r.train_steps_phase2 > 0
               ? std::to_string(r.train_steps_phase1) + "+" + std::to_string(r.train_steps_phase2)
               : "-")
       << " | " << (r.params > 0 ? F(r.params / 1e6, "%.2f") + " M" : "-") << " | "
       << (r.flops_per_view > 0 ? F(r.flops_per_view / 1e9, "%.3f") : "-") << " | "
       << F(r.coverage_spearman) << " | " << F(r.pose_dependence)
       << (r.pose_dependence < model::kPoseDependenceWarn ? " (collapsed)" : "") << " |\n";
  }
}

// Seed spread (GAN stability), when some combination ran with several seeds.
void WriteSeedSpread(const std::vector<ResultRow>& rows, std::ostringstream& md) {
  std::map<std::string, std::vector<const ResultRow*>> groups;
  for (const auto& r : rows) groups[r.method + "|" + r.setting + "|" + r.size].push_back(&r);
  bool any_multi = false;
  for (const auto& g : groups) any_multi = any_multi || g.second.size() > 1;
  if (!any_multi) return;
  md << "\n## Seed spread (training stability)\n\n"
        "| method | setting | size | seeds | PSNR mean ± sd (min-max) | SSIM mean ± sd | "
        "LPIPS-Sq mean ± sd |\n|---|---|---|---|---|---|---|\n";
  for (const auto& g : groups) {
    if (g.second.size() < 2) continue;
    std::vector<double> p, s, l;
    for (const auto* r : g.second) {
      p.push_back(r->psnr);
      s.push_back(r->ssim);
      l.push_back(r->lpips);
    }
    const auto sp = ComputeSpread(p), ss = ComputeSpread(s), sl = ComputeSpread(l);
    const auto* r0 = g.second.front();
    md << "| " << r0->method << " | " << r0->setting << " | " << r0->size << " | "
       << g.second.size() << " | " << F(sp.mean) << " ± " << F(sp.stddev) << " (" << F(sp.min)
       << "-" << F(sp.max) << ") | " << F(ss.mean, "%.3f") << " ± " << F(ss.stddev, "%.3f")
       << " | " << F(sl.mean, "%.3f") << " ± " << F(sl.stddev, "%.3f") << " |\n";
  }
}

// Coverage score as an error predictor.
void WriteCoverage(const ReportInputs& in, std::ostringstream& md) {
  md << "\n## Coverage score vs error\n\nSpearman rank correlation between the coverage score "
        "of each test pose (model/coverage.h: 1 on the training trajectory, falling with the "
        "distance) and the PSNR of its view, per method (mean over its rows). Positive = the "
        "score ranks views the way their quality does, so a robot can refuse low-score "
        "views.\n\n| method | mean rho | rows |\n|---|---|---|\n";
  for (const auto& m : in.chart_inputs.methods) {
    std::vector<double> v;
    for (const auto& r : in.chart_inputs.rows)
      if (r.method == m) v.push_back(r.coverage_spearman);
    if (v.empty()) continue;
    const auto s = ComputeSpread(v);
    md << "| " << m << " | " << F(s.mean) << " | " << s.n << " of " << v.size() << " |\n";
  }
}

void WriteChartLinks(const ChartOutputs& charts, std::ostringstream& md) {
  md << "\n## Charts\n\n";
  if (!charts.note.empty()) md << "> " << charts.note << "\n\n";
  for (const auto& c : charts.charts) {
    if (charts.gnuplot_ran)
      md << "![" << c << "](charts/" << c << ".png)\n\n[" << c << ".svg](charts/" << c
         << ".svg)\n\n";
    else
      md << "- `charts/" << c << ".gp` (not rendered)\n";
  }
}

// Stability, auto-size and strips: each section only when the run has it.
void WriteOptionalSections(const ReportInputs& in, std::ostringstream& md) {
  if (!in.chart_inputs.stability.empty()) {
    md << "\n## Stability: where methods fail\n\nOffsets swept outward from training poses of "
          "setting "
       << in.chart_inputs.primary_setting
       << "'s models (see stability.csv); exact ground truth rendered by the sim scene.\n\n";
    for (const auto& line :
         StabilitySummary(in.chart_inputs.stability, in.chart_inputs.methods, in.chart_inputs.threshold_db))
      md << "- " << line << "\n";
  }
  if (!in.auto_size.empty()) {
    md << "\n## Model size (auto-size)\n\n";
    for (const auto& a : in.auto_size) md << a << "\n\n";
  }
  if (!in.strips.empty()) {
    md << "\n## Image strips\n\nGround truth (top row) next to every method for the same test "
          "poses: RGB | depth (turbo colour map, black = invalid/hole).\n\n";
    for (const auto& s : in.strips)
      md << "### setting " << s.first << "\n\n![strip " << s.first << "](" << s.second << ")\n\n";
  }
}

}  // namespace

std::string RenderReportMarkdown(const ReportInputs& in) {
  std::ostringstream md;
  WriteHeader(in, md);
  WriteResultsTable(in.chart_inputs.rows, md);
  WriteSeedSpread(in.chart_inputs.rows, md);
  WriteCoverage(in, md);
  WriteChartLinks(in.charts, md);
  WriteOptionalSections(in, md);
  return md.str();
}

}  // namespace p2i::eval
