/// @file stats.cc
#include "eval/stats.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace p2i::eval {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Fmt(const char* format, double a, double b = 0.0, double c = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), format, a, b, c);
  return buf;
}
}  // namespace

Spread ComputeSpread(const std::vector<double>& values) {
  std::vector<double> v;
  for (double x : values)
    if (std::isfinite(x)) v.push_back(x);
  Spread s;
  s.n = v.size();
  if (v.empty()) {
    s.mean = s.stddev = s.min = s.max = kNaN;
    return s;
  }
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / v.size();
  double ss = 0.0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.stddev = v.size() > 1 ? std::sqrt(ss / (v.size() - 1)) : 0.0;
  s.min = *std::min_element(v.begin(), v.end());
  s.max = *std::max_element(v.begin(), v.end());
  return s;
}

std::vector<double> FractionalRanks(const std::vector<double>& values) {
  const size_t n = values.size();
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return values[a] < values[b]; });
  std::vector<double> ranks(n);
  for (size_t i = 0; i < n;) {
    size_t j = i;
    while (j + 1 < n && values[order[j + 1]] == values[order[i]]) ++j;
    const double r = (static_cast<double>(i) + static_cast<double>(j)) / 2.0 + 1.0;
    for (size_t k = i; k <= j; ++k) ranks[order[k]] = r;
    i = j + 1;
  }
  return ranks;
}

double SpearmanRho(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size())
    throw std::invalid_argument("SpearmanRho: x and y differ in length");
  std::vector<double> a, b;
  for (size_t i = 0; i < x.size(); ++i) {
    if (std::isfinite(x[i]) && std::isfinite(y[i])) {
      a.push_back(x[i]);
      b.push_back(y[i]);
    }
  }
  if (a.size() < 3) return kNaN;
  const std::vector<double> ra = FractionalRanks(a), rb = FractionalRanks(b);
  const double n = static_cast<double>(ra.size());
  const double ma = std::accumulate(ra.begin(), ra.end(), 0.0) / n;
  const double mb = std::accumulate(rb.begin(), rb.end(), 0.0) / n;
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < ra.size(); ++i) {
    sab += (ra[i] - ma) * (rb[i] - mb);
    saa += (ra[i] - ma) * (ra[i] - ma);
    sbb += (rb[i] - mb) * (rb[i] - mb);
  }
  if (saa <= 0.0 || sbb <= 0.0) return kNaN;
  return sab / std::sqrt(saa * sbb);
}

std::vector<size_t> ParetoFront(const std::vector<ParetoPoint>& points, bool maximize_x,
                                bool maximize_y) {
  auto finite = [](const ParetoPoint& p) { return std::isfinite(p.x) && std::isfinite(p.y); };
  // "a at least as good as b" per axis.
  auto ge_x = [&](double a, double b) { return maximize_x ? a >= b : a <= b; };
  auto ge_y = [&](double a, double b) { return maximize_y ? a >= b : a <= b; };
  std::vector<size_t> front;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!finite(points[i])) continue;
    bool dominated = false;
    for (size_t j = 0; j < points.size() && !dominated; ++j) {
      if (j == i || !finite(points[j])) continue;
      const auto& p = points[j];
      const auto& q = points[i];
      if (ge_x(p.x, q.x) && ge_y(p.y, q.y) && (p.x != q.x || p.y != q.y)) dominated = true;
    }
    if (!dominated) front.push_back(i);
  }
  return front;
}

namespace {

/// Fewer parameters, then fewer FLOPs, then more views/s.
bool Cheaper(const SizeCandidate& a, const SizeCandidate& b) {
  if (a.params != b.params) return a.params < b.params;
  if (a.flops != b.flops) return a.flops < b.flops;
  return a.views_per_s > b.views_per_s;
}

}  // namespace

AutoSizeChoice ChooseAutoSize(const std::vector<SizeCandidate>& c, double margin_db,
                              const std::string& noun) {
  if (!std::isfinite(margin_db) || margin_db < 0.0)
    throw std::invalid_argument("auto-size margin must be a finite number >= 0 dB");
  AutoSizeChoice out;
  for (size_t i = 0; i < c.size(); ++i) {
    if (!std::isfinite(c[i].psnr_db)) continue;
    if (out.best_index < 0 || c[i].psnr_db > c[out.best_index].psnr_db) out.best_index = int(i);
  }
  if (out.best_index < 0) {
    out.reason = "no " + noun + " of the ladder has a measured PSNR: nothing to choose";
    return out;
  }
  out.best_psnr_db = c[out.best_index].psnr_db;
  const double floor_db = out.best_psnr_db - margin_db;
  for (size_t i = 0; i < c.size(); ++i) {
    if (!std::isfinite(c[i].psnr_db) || c[i].psnr_db < floor_db) continue;
    if (out.index < 0 || Cheaper(c[i], c[out.index])) out.index = int(i);
  }
  const auto& pick = c[out.index];
  const auto& best = c[out.best_index];
  const std::string cheapest = "the cheapest (fewest parameters, then FLOPs, then most views/s) of the " + noun + "s within";
  std::string r = "picked '" + pick.name + "' (" + Fmt("%.3g M params, %.3g GFLOP/view, ", pick.params / 1e6, pick.flops / 1e9) +
                  Fmt("%.2f dB PSNR, %.1f views/s)", pick.psnr_db, pick.views_per_s) + ": ";
  std::string within;
  for (size_t i = 0; i < c.size(); ++i)
    if (std::isfinite(c[i].psnr_db) && c[i].psnr_db >= floor_db)
      within += (within.empty() ? "'" : ", '") + c[i].name + "'";
  if (out.index == out.best_index) {
    r += "it has the best PSNR of the ladder and is " + cheapest + " " +
         Fmt("%.2f dB of it (", margin_db) + within + ")";
  } else {
    r += "the best is '" + best.name + "' at " + Fmt("%.2f dB", best.psnr_db) + " (" +
         Fmt("%.3g M params, %.1f views/s", best.params / 1e6, best.views_per_s) + "); '" + pick.name + "' is " +
         Fmt("%.2f dB below it, within the %.2f dB margin, and ", best.psnr_db - pick.psnr_db, margin_db) + cheapest + " it (" + within + ")";
  }
  std::string cheaper;
  for (size_t i = 0; i < c.size(); ++i) {
    if (int(i) == out.index || !std::isfinite(c[i].psnr_db)) continue;
    if (Cheaper(c[i], pick))
      cheaper += (cheaper.empty() ? "" : ", ") + ("'" + c[i].name + "' ") +
                 Fmt("%.2f dB (%.2f dB below the best)", c[i].psnr_db, best.psnr_db - c[i].psnr_db);
  }
  if (!cheaper.empty()) r += "; cheaper " + noun + "s fall outside the margin: " + cheaper;
  out.reason = r + ".";
  return out;
}

double FirstDistanceBelow(const std::vector<double>& distances, const std::vector<double>& quality,
                          double threshold) {
  const size_t n = std::min(distances.size(), quality.size());
  for (size_t i = 0; i < n; ++i)
    if (std::isfinite(quality[i]) && quality[i] < threshold) return distances[i];
  return kNaN;
}

}  // namespace p2i::eval
