/// @file results.cc
#include "eval/results.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "scene/capture.h"
#include "util/json_number.h"

namespace p2i::eval {
namespace {

using nlohmann::json;

std::string Num(double v, int precision = 6) {
  if (!std::isfinite(v)) return "NA";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
  return buf;
}

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += (c == '"') ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

json J(double v) { return util::NumberOrNull(v); }
double D(const json& j, const char* key) {
  if (!j.contains(key) || j.at(key).is_null()) return std::nan("");
  return j.at(key).get<double>();
}

}  // namespace

std::string ResultRow::Key() const {
  return method + "|" + setting + "|" + size + "|" + std::to_string(seed);
}

std::string CsvHeader() {
  return "method,method_type,setting,size,resolution,seed,train_frames,test_views,psnr_db,ssim,"
         "lpips_squeeze,depth_abs_rel,depth_rmse_m,depth_valid_fraction,views_per_s,"
         "latency_p50_ms,latency_p99_ms,threads,train_s,train_steps_phase1,train_steps_phase2,"
         "params,flops_per_view,coverage_spearman,pose_dependence,height";
}

std::string CsvLine(const ResultRow& r) {
  std::ostringstream os;
  os << CsvField(r.method) << ',' << r.method_type << ',' << r.setting << ',' << CsvField(r.size)
     << ',' << r.resolution << ',' << r.seed << ',' << r.train_frames << ',' << r.test_views << ','
     << Num(r.psnr) << ',' << Num(r.ssim) << ',' << Num(r.lpips) << ',' << Num(r.depth_abs_rel)
     << ',' << Num(r.depth_rmse_m) << ',' << Num(r.depth_valid_fraction) << ','
     << Num(r.views_per_s) << ',' << Num(r.latency_p50_ms) << ',' << Num(r.latency_p99_ms) << ','
     << r.threads << ',' << Num(r.train_s) << ',' << r.train_steps_phase1 << ','
     << r.train_steps_phase2 << ',' << Num(r.params, 10) << ',' << Num(r.flops_per_view, 10)
     << ',' << Num(r.coverage_spearman) << ',' << Num(r.pose_dependence) << ','
     << (r.height > 0 ? r.height : r.resolution);
  return os.str();
}

std::string ResultsToJson(const std::vector<ResultRow>& rows, const std::string& config_hash) {
  json out;
  out["format"] = "p2i_bench_results";
  out["version"] = 1;
  out["config_hash"] = config_hash;
  out["lpips_label"] = "LPIPS-Squeeze";
  json arr = json::array();
  for (const auto& r : rows) {
    json j;
    j["method"] = r.method;
    j["method_type"] = r.method_type;
    j["setting"] = r.setting;
    j["size"] = r.size;
    j["resolution"] = r.resolution;
    j["height"] = r.height > 0 ? r.height : r.resolution;
    j["seed"] = r.seed;
    j["train_frames"] = r.train_frames;
    j["test_views"] = r.test_views;
    j["psnr_db"] = J(r.psnr);
    j["ssim"] = J(r.ssim);
    j["lpips_squeeze"] = J(r.lpips);
    j["depth_abs_rel"] = J(r.depth_abs_rel);
    j["depth_rmse_m"] = J(r.depth_rmse_m);
    j["depth_valid_fraction"] = J(r.depth_valid_fraction);
    j["views_per_s"] = J(r.views_per_s);
    j["latency_p50_ms"] = J(r.latency_p50_ms);
    j["latency_p99_ms"] = J(r.latency_p99_ms);
    j["threads"] = r.threads;
    j["train_s"] = J(r.train_s);
    j["train_steps_phase1"] = r.train_steps_phase1;
    j["train_steps_phase2"] = r.train_steps_phase2;
    j["params"] = J(r.params);
    j["flops_per_view"] = J(r.flops_per_view);
    j["coverage_spearman"] = J(r.coverage_spearman);
    j["pose_dependence"] = J(r.pose_dependence);
    json views = json::array();
    for (const auto& v : r.views)
      views.push_back({{"id", v.id}, {"psnr_db", J(v.psnr)}, {"ssim", J(v.ssim)},
                       {"lpips_squeeze", J(v.lpips)}, {"coverage", J(v.coverage)}});
    j["views"] = views;
    arr.push_back(j);
  }
  out["rows"] = arr;
  return out.dump(1) + "\n";
}

std::vector<ResultRow> ParseResultsJson(const std::string& text, std::string* config_hash) {
  json in;
  try {
    in = json::parse(text);
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("malformed results JSON: ") + e.what());
  }
  if (in.value("format", "") != "p2i_bench_results")
    throw std::runtime_error("not a p2i bench results file (format != p2i_bench_results)");
  if (config_hash) *config_hash = in.value("config_hash", "");
  std::vector<ResultRow> rows;
  try {
    for (const auto& j : in.at("rows")) {
      ResultRow r;
      r.method = j.at("method");
      r.method_type = j.at("method_type");
      r.setting = j.at("setting");
      r.size = j.at("size");
      r.resolution = j.at("resolution");
      r.height = j.value("height", r.resolution);  // files before 4:3 sizes: square
      r.seed = j.at("seed");
      r.train_frames = j.value("train_frames", 0);
      r.test_views = j.value("test_views", 0);
      r.psnr = D(j, "psnr_db");
      r.ssim = D(j, "ssim");
      r.lpips = D(j, "lpips_squeeze");
      r.depth_abs_rel = D(j, "depth_abs_rel");
      r.depth_rmse_m = D(j, "depth_rmse_m");
      r.depth_valid_fraction = D(j, "depth_valid_fraction");
      r.views_per_s = D(j, "views_per_s");
      r.latency_p50_ms = D(j, "latency_p50_ms");
      r.latency_p99_ms = D(j, "latency_p99_ms");
      r.threads = j.value("threads", 1);
      r.train_s = D(j, "train_s");
      r.train_steps_phase1 = j.value("train_steps_phase1", 0);
      r.train_steps_phase2 = j.value("train_steps_phase2", 0);
      r.params = D(j, "params");
      r.flops_per_view = D(j, "flops_per_view");
      r.coverage_spearman = D(j, "coverage_spearman");
      r.pose_dependence = j.contains("pose_dependence") ? D(j, "pose_dependence") : std::nan("");
      if (j.contains("views")) {
        for (const auto& v : j.at("views")) {
          ViewRecord rec;
          rec.id = v.value("id", "");
          rec.psnr = D(v, "psnr_db");
          rec.ssim = D(v, "ssim");
          rec.lpips = D(v, "lpips_squeeze");
          rec.coverage = D(v, "coverage");
          r.views.push_back(rec);
        }
      }
      rows.push_back(std::move(r));
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(std::string("malformed results JSON row: ") + e.what());
  }
  return rows;
}

ResultsStore::ResultsStore(std::string dir, std::string config_hash)
    : dir_(std::move(dir)), config_hash_(std::move(config_hash)) {}

std::string ResultsStore::csv_path() const { return dir_ + "/results.csv"; }
std::string ResultsStore::json_path() const { return dir_ + "/results.json"; }

size_t ResultsStore::LoadExisting() {
  if (!std::filesystem::exists(json_path())) return 0;
  std::ifstream in(json_path());
  std::stringstream ss;
  ss << in.rdbuf();
  std::string hash;
  std::vector<ResultRow> rows;
  try {
    rows = ParseResultsJson(ss.str(), &hash);
  } catch (const std::exception& e) {
    throw std::runtime_error(json_path() + ": " + e.what());
  }
  if (hash != config_hash_)
    throw std::runtime_error(json_path() + " holds results of another configuration (config hash " +
                             hash + ", this one " + config_hash_ +
                             "): pass --fresh to discard them or choose another --out");
  rows_ = std::move(rows);
  return rows_.size();
}

bool ResultsStore::Has(const std::string& key) const {
  for (const auto& r : rows_)
    if (r.Key() == key) return true;
  return false;
}

void ResultsStore::Add(ResultRow row) {
  for (auto& r : rows_) {
    if (r.Key() == row.Key()) {
      r = std::move(row);
      Flush();
      return;
    }
  }
  rows_.push_back(std::move(row));
  Flush();
}

void ResultsStore::Flush() const {
  std::filesystem::create_directories(dir_);
  std::string csv = CsvHeader() + "\n";
  for (const auto& r : rows_) csv += CsvLine(r) + "\n";
  scene::WriteFileAtomic(csv_path(), csv);
  scene::WriteFileAtomic(json_path(), ResultsToJson(rows_, config_hash_));
}

}  // namespace p2i::eval
