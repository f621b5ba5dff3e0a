/// @file charts.cc
#include "eval/charts.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>

#include "eval/stats.h"
#include "scene/capture.h"

namespace p2i::eval {
namespace fs = std::filesystem;
namespace {

std::string V(double v) {
  if (!std::isfinite(v)) return "?";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}
std::string Q(const std::string& s) { return "\"" + s + "\""; }

// The gnuplot script: the same body rendered to PNG and to SVG.
std::string Script(const std::string& stem, const std::string& body) {
  std::ostringstream os;
  os << "# " << stem << ": written by p2i bench; run `gnuplot " << stem << ".gp` in this folder.\n"
     << "set datafile missing '?'\nset grid\nset key outside right top\n"
     << "set terminal pngcairo size 960,600 noenhanced font ',10'\nset output '" << stem
     << ".png'\n"
     << body << "\nset terminal svg size 960,600 noenhanced\nset output '" << stem << ".svg'\n"
     << body << "\nunset output\n";
  return os.str();
}

bool HaveGnuplot(const std::string& cmd) {
  const std::string probe = "command -v " + cmd + " >/dev/null 2>&1";
  return std::system(probe.c_str()) == 0;
}

}  // namespace

double MeanOver(const std::vector<ResultRow>& rows, const std::string& method,
                const std::string& setting, const std::string& size, const std::string& field) {
  std::vector<double> v;
  for (const auto& r : rows) {
    if (r.method != method || r.setting != setting || r.size != size) continue;
    if (field == "psnr") v.push_back(r.psnr);
    else if (field == "ssim") v.push_back(r.ssim);
    else if (field == "lpips") v.push_back(r.lpips);
    else if (field == "views_per_s") v.push_back(r.views_per_s);
    else if (field == "params") v.push_back(r.params);
    else if (field == "flops") v.push_back(r.flops_per_view);
    else if (field == "abs_rel") v.push_back(r.depth_abs_rel);
  }
  return ComputeSpread(v).mean;
}

namespace {

// Writes the chart files into one folder and records the chart stems.
struct ChartWriter {
  std::string dir;
  ChartOutputs* out;
  void Write(const std::string& name, const std::string& text) const {
    scene::WriteFileAtomic((fs::path(dir) / name).string(), text);
  }
  void Add(const std::string& stem) const { out->charts.push_back(stem); }
};

// Accuracy vs speed on the primary setting: one point per method x size (mean over seeds), with
// the Pareto front; PSNR always, LPIPS-Squeeze when any row has it. Returns whether one has.
bool WriteAccuracySpeed(const ChartInputs& in, const ChartWriter& w) {
  struct Pt {
    std::string label;
    double speed, psnr, lpips;
  };
  std::vector<Pt> pts;
  for (const auto& m : in.methods)
    for (const auto& s : in.sizes) {
      const double psnr = MeanOver(in.rows, m, in.primary_setting, s, "psnr");
      if (!std::isfinite(psnr)) continue;
      const double sp = MeanOver(in.rows, m, in.primary_setting, s, "views_per_s");
      pts.push_back({in.sizes.size() > 1 ? m + "/" + s : m, sp > 0 ? sp : NAN, psnr,
                     MeanOver(in.rows, m, in.primary_setting, s, "lpips")});
    }
  bool any_lpips = false;
  {
    std::ostringstream dat;
    dat << "# label views_per_s psnr_db lpips_squeeze (setting " << in.primary_setting
        << ", mean over seeds)\n";
    for (const auto& p : pts) {
      dat << Q(p.label) << ' ' << V(p.speed) << ' ' << V(p.psnr) << ' ' << V(p.lpips) << '\n';
      any_lpips = any_lpips || std::isfinite(p.lpips);
    }
    w.Write("accuracy_speed.dat", dat.str());
    for (int which = 0; which < 2; ++which) {
      const bool psnr = which == 0;
      if (!psnr && !any_lpips) continue;
      std::vector<ParetoPoint> pp;
      for (const auto& p : pts) pp.push_back({p.speed, psnr ? p.psnr : p.lpips});
      auto front = ParetoFront(pp, true, psnr);
      std::sort(front.begin(), front.end(), [&](size_t a, size_t b) { return pp[a].x < pp[b].x; });
      std::ostringstream fd;
      fd << "# Pareto front (non-dominated: faster or " << (psnr ? "higher PSNR" : "lower LPIPS-Squeeze")
         << ")\n";
      for (size_t i : front) fd << Q(pts[i].label) << ' ' << V(pp[i].x) << ' ' << V(pp[i].y) << '\n';
      const std::string stem = psnr ? "accuracy_vs_speed_psnr" : "accuracy_vs_speed_lpips";
      w.Write(stem + "_front.dat", fd.str());
      const int col = psnr ? 3 : 4;
      std::ostringstream body;
      body << "set logscale x\nset xlabel 'views/s at batch 1 (log scale)'\nset ylabel '"
           << (psnr ? "PSNR (dB), higher is better" : "LPIPS-Squeeze, lower is better") << "'\n"
           << "set offsets graph 0.08, graph 0.08, graph 0.1, graph 0.05\n"
           << "set title 'Accuracy vs speed, setting " << in.primary_setting
           << " (mean over seeds; dashed: Pareto front)'\n"
           << "plot 'accuracy_speed.dat' using 2:" << col << " with points pt 7 ps 1.3 title 'method', \\\n"
           << "  'accuracy_speed.dat' using 2:" << col << ":1 with labels offset 0,1 notitle, \\\n"
           << "  '" << stem << "_front.dat' using 2:3 with linespoints dt 2 lw 2 pt 6 ps 2.5 title 'Pareto front'";
      w.Write(stem + ".gp", Script(stem, body.str()));
      w.Add(stem);
    }
  }

  return any_lpips;
}

// Quality per setting at the first size (mean over seeds): PSNR, and LPIPS-Squeeze if any.
void WriteQualityPerSetting(const ChartInputs& in, bool any_lpips, const ChartWriter& w) {
  if (!in.sizes.empty()) {
    for (int which = 0; which < 2; ++which) {
      const bool psnr = which == 0;
      if (!psnr && !any_lpips) continue;
      std::ostringstream dat;
      dat << "setting";
      for (const auto& m : in.methods) dat << ' ' << Q(m);
      dat << '\n';
      for (const auto& s : in.settings) {
        dat << s;
        for (const auto& m : in.methods)
          dat << ' ' << V(MeanOver(in.rows, m, s, in.sizes.front(), psnr ? "psnr" : "lpips"));
        dat << '\n';
      }
      const std::string stem = psnr ? "quality_per_setting_psnr" : "quality_per_setting_lpips";
      w.Write(stem + ".dat", dat.str());
      std::ostringstream body;
      body << "set xlabel 'setting (a: N of 100 held out; b: adjacent trajectory; c: cross trajectory)'\n"
           << "set ylabel '" << (psnr ? "PSNR (dB)" : "LPIPS-Squeeze") << "'\nset title 'Quality per setting, size "
           << in.sizes.front() << " (mean over seeds)'\nset offsets 0.3, 0.3, 0, 0\n"
           << "plot for [i=2:" << in.methods.size() + 1 << "] '" << stem
           << ".dat' using i:xtic(1) with linespoints lw 2 pt 7 title columnheader(i)";
      w.Write(stem + ".gp", Script(stem, body.str()));
      w.Add(stem);
    }
  }

}

// Stability: PSNR against the offset from the training poses, per method and kind.
void WriteStability(const ChartInputs& in, const ChartWriter& w) {
  for (const std::string kind : {"translation", "rotation"}) {
    std::vector<double> offsets;
    for (const auto& p : in.stability)
      if (p.kind == kind && std::find(offsets.begin(), offsets.end(), p.offset) == offsets.end())
        offsets.push_back(p.offset);
    if (offsets.empty()) continue;
    std::sort(offsets.begin(), offsets.end());
    std::vector<std::string> methods;
    for (const auto& m : in.methods)
      for (const auto& p : in.stability)
        if (p.kind == kind && p.method == m) {
          methods.push_back(m);
          break;
        }
    std::ostringstream dat;
    dat << "offset";
    for (const auto& m : methods) dat << ' ' << Q(m);
    dat << '\n';
    for (double o : offsets) {
      dat << V(o);
      for (const auto& m : methods) {
        double v = NAN;
        for (const auto& p : in.stability)
          if (p.kind == kind && p.method == m && p.offset == o) v = p.psnr;
        dat << ' ' << V(v);
      }
      dat << '\n';
    }
    const std::string stem = "stability_" + kind;
    w.Write(stem + ".dat", dat.str());
    std::ostringstream body;
    body << "set xlabel '" << (kind == "translation" ? "translation offset from a training pose (m)"
                                                     : "rotation offset from a training pose (deg)")
         << "'\nset ylabel 'PSNR (dB; the 100 dB cap of exact copies is clipped)'\nset yrange [*:*<50]\n"
         << "set title 'Stability: quality away from the training trajectory (threshold "
         << V(in.threshold_db) << " dB)'\n"
         << "plot for [i=2:" << methods.size() + 1 << "] '" << stem
         << ".dat' using 1:i with linespoints lw 2 pt 7 title columnheader(i), " << V(in.threshold_db)
         << " with lines dt 3 lc 'black' title 'threshold'";
    w.Write(stem + ".gp", Script(stem, body.str()));
    w.Add(stem);
  }

}

// Size ladder: PSNR against parameters of the learned methods (only with several sizes).
void WriteLadder(const ChartInputs& in, const ChartWriter& w) {
  if (in.sizes.size() > 1) {
    std::vector<std::string> plots;
    for (const auto& m : in.methods) {
      std::ostringstream dat;
      dat << "# size params psnr_db views_per_s (method " << m << ", setting " << in.primary_setting
          << ")\n";
      int n = 0;
      for (const auto& s : in.sizes) {
        const double params = MeanOver(in.rows, m, in.primary_setting, s, "params");
        if (!(params > 0)) continue;
        ++n;
        dat << Q(s) << ' ' << V(params) << ' ' << V(MeanOver(in.rows, m, in.primary_setting, s, "psnr"))
            << ' ' << V(MeanOver(in.rows, m, in.primary_setting, s, "views_per_s")) << '\n';
      }
      if (n == 0) continue;
      const std::string file = "ladder_" + std::to_string(plots.size()) + ".dat";
      w.Write(file, dat.str());
      plots.push_back("'" + file + "' using 2:3 with linespoints lw 2 pt 7 title '" + m + "', '" +
                      file + "' using 2:3:1 with labels offset 0,1 notitle");
    }
    if (!plots.empty()) {
      std::ostringstream body;
      body << "set logscale x\nset xlabel 'parameters (log scale)'\nset ylabel 'PSNR (dB)'\n"
           << "set offsets graph 0.1, graph 0.1, graph 0.1, graph 0.05\n"
           << "set title 'Model size ladder, setting " << in.primary_setting << "'\nplot ";
      for (size_t i = 0; i < plots.size(); ++i) body << (i ? ", \\\n  " : "") << plots[i];
      w.Write("ladder.gp", Script("ladder", body.str()));
      w.Add("ladder");
    }
  }

}

// Runs gnuplot on every chart script, or says how to once it is installed.
void RunGnuplot(const std::string& dir, const std::string& gnuplot_command, ChartOutputs* out) {
  if (!HaveGnuplot(gnuplot_command)) {
    out->note = "gnuplot not found: the charts' data (.dat) and scripts (.gp) are in " + dir +
               "; run `gnuplot NAME.gp` there once it is installed (Debian: gnuplot-nox)";
    return;
  }
  bool all_ok = true;
  for (const auto& stem : out->charts) {
    const std::string cmd = "cd '" + dir + "' && " + gnuplot_command + " '" + stem + ".gp' 2>'" +
                            stem + ".log'";
    const int rc = std::system(cmd.c_str());
    const bool ok = rc == 0 && fs::exists(fs::path(dir) / (stem + ".png"));
    if (ok) fs::remove(fs::path(dir) / (stem + ".log"));
    all_ok = all_ok && ok;
  }
  out->gnuplot_ran = true;
  if (!all_ok) out->note = "gnuplot failed on some charts: see the .log files in " + dir;
}

}  // namespace

ChartOutputs WriteCharts(const ChartInputs& in, const std::string& dir,
                         const std::string& gnuplot_command) {
  fs::create_directories(dir);
  ChartOutputs out;
  const ChartWriter w{dir, &out};
  const bool any_lpips = WriteAccuracySpeed(in, w);
  WriteQualityPerSetting(in, any_lpips, w);
  WriteStability(in, w);
  WriteLadder(in, w);
  RunGnuplot(dir, gnuplot_command, &out);
  return out;
}

}  // namespace p2i::eval
