/// @file results_test.cc
/// @brief results.csv / results.json: columns, missing values, atomic rewrite, resume rules.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <catch2/catch.hpp>

#include "eval/report.h"
#include "tests/read_file.h"
#include "eval/results.h"

namespace fs = std::filesystem;
using namespace p2i::eval;

namespace {
ResultRow Row(const std::string& method, int seed, double lpips) {
  ResultRow r;
  r.method = method;
  r.method_type = method == "p2i" ? "p2i" : "nearest";
  r.setting = "a3";
  r.size = "r128";
  r.resolution = 128;
  r.seed = seed;
  r.psnr = 21.5;
  r.ssim = 0.61;
  r.lpips = lpips;
  r.views_per_s = 50;
  r.params = 920000;
  r.pose_dependence = method == "p2i" ? 0.875 : NAN;
  r.views = {{"seq-01/000100", 21.0, 0.6, lpips, 0.9}};
  return r;
}
}  // namespace

TEST_CASE("ResultsStore writes one CSV/JSON row per completed combination, NA for missing",
          "[unit]") {
  const fs::path dir = fs::temp_directory_path() / ("p2i_results_" + std::to_string(getpid()));
  fs::remove_all(dir);
  {
    ResultsStore store(dir.string(), "hash1");
    CHECK(store.LoadExisting() == 0);
    store.Add(Row("nearest", 1, NAN));  // LPIPS missing: NA / null, never 0
    store.Add(Row("p2i", 1, 0.25));
    store.Add(Row("p2i", 1, 0.20));  // same key: replaces
    CHECK(store.rows().size() == 2);
  }
  const std::string csv = p2i::testing::ReadFile(dir / "results.csv");
  std::istringstream lines(csv);
  std::string header, l1, l2, extra;
  std::getline(lines, header);
  std::getline(lines, l1);
  std::getline(lines, l2);
  CHECK_FALSE(static_cast<bool>(std::getline(lines, extra)));
  CHECK(header.find("lpips_squeeze") != std::string::npos);
  CHECK(header.find("latency_p99_ms") != std::string::npos);
  CHECK(header.find("flops_per_view") != std::string::npos);
  // The last two columns: pose_dependence, then height (appended with 4:3 sizes; square here).
  const auto second_last = [](const std::string& line) {
    const std::string head = line.substr(0, line.rfind(','));
    return head.substr(head.rfind(',') + 1);
  };
  CHECK(header.substr(header.rfind(',') + 1) == "height");
  CHECK(second_last(header) == "pose_dependence");
  CHECK(second_last(l1) == "NA");  // nearest: not computed
  CHECK(second_last(l2) == "0.875");
  CHECK(l1.substr(l1.rfind(',') + 1) == "128");
  CHECK(l1.rfind("nearest,nearest,a3,r128,128,1,", 0) == 0);
  CHECK(l1.find(",NA,") != std::string::npos);
  CHECK(l2.find(",0.2,") != std::string::npos);
  // No temporary files are left behind.
  for (const auto& e : fs::directory_iterator(dir))
    CHECK(e.path().filename().string().find("tmp") == std::string::npos);

  std::string hash;
  const auto rows = ParseResultsJson(p2i::testing::ReadFile(dir / "results.json"), &hash);
  CHECK(hash == "hash1");
  REQUIRE(rows.size() == 2);
  CHECK(std::isnan(rows[0].lpips));
  CHECK(rows[1].lpips == Approx(0.20));
  CHECK(rows[1].params == Approx(920000));
  CHECK(std::isnan(rows[0].pose_dependence));
  CHECK(rows[1].pose_dependence == Approx(0.875));
  REQUIRE(rows[1].views.size() == 1);
  CHECK(rows[1].views[0].coverage == Approx(0.9));
  CHECK(p2i::testing::ReadFile(dir / "results.json").find("\"lpips_squeeze\": null") != std::string::npos);

  // Resume: the same config hash reloads the rows; another one is refused with advice.
  ResultsStore again(dir.string(), "hash1");
  CHECK(again.LoadExisting() == 2);
  CHECK(again.Has("p2i|a3|r128|1"));
  CHECK_FALSE(again.Has("p2i|a3|r128|2"));
  ResultsStore other(dir.string(), "hash2");
  try {
    other.LoadExisting();
    FAIL("expected an error");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("--fresh") != std::string::npos);
    CHECK(std::string(e.what()).find("results.json") != std::string::npos);
  }
  fs::remove_all(dir);
}

TEST_CASE("the bench report has a pose-dep column and marks a collapsed row", "[unit]") {
  ReportInputs in;
  ResultRow learned = Row("p2i", 1, 0.2);
  learned.pose_dependence = 0.83;
  ResultRow collapsed = Row("p2i", 2, 0.3);
  collapsed.pose_dependence = 0.12;
  in.chart_inputs.rows = {Row("nearest", 1, NAN), learned, collapsed};
  const std::string md = RenderReportMarkdown(in);
  CHECK(md.find("| rho | pose-dep |") != std::string::npos);
  CHECK(md.find("| 0.83 |") != std::string::npos);
  CHECK(md.find("| 0.12 (collapsed) |") != std::string::npos);
  CHECK(md.find("(collapsed)") == md.rfind("(collapsed)"));  // only the collapsed row
}
