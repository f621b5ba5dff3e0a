/// @file charts_test.cc
/// @brief Charts: data and gnuplot scripts always; PNG + SVG when gnuplot runs; a missing gnuplot
/// is a note, not a failure. Strips: ground truth and methods side by side.
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <catch2/catch.hpp>
#include <opencv2/imgcodecs.hpp>

#include "eval/charts.h"
#include "eval/report.h"
#include "tests/read_file.h"
#include "eval/strips.h"

namespace fs = std::filesystem;
using namespace p2i::eval;

namespace {
ChartInputs Inputs() {
  ChartInputs in;
  in.settings = {"a1", "b", "c"};  // c has no rows: missing values
  in.methods = {"nearest", "p2i"};
  in.sizes = {"tiny", "small"};
  in.primary_setting = "a1";
  auto row = [](std::string m, std::string set, std::string size, double psnr, double speed, double params) {
    ResultRow r;
    r.method = m;
    r.setting = set;
    r.size = size;
    r.psnr = psnr;
    r.lpips = NAN;
    r.views_per_s = speed;
    r.params = params;
    return r;
  };
  in.rows = {row("nearest", "a1", "tiny", 18, 5000, 0), row("nearest", "b", "tiny", 16, 5000, 0),
             row("p2i", "a1", "tiny", 20, 40, 1e5), row("p2i", "a1", "small", 21, 50, 4e5),
             row("p2i", "b", "tiny", 19, 100, 1e5)};
  in.stability = {{"nearest", "translation", 0.0, 100, 1, 0, 2}, {"nearest", "translation", 0.2, 15, 0.5, 0.2, 2},
                  {"p2i", "translation", 0.0, 20, 0.6, 0, 2}, {"p2i", "translation", 0.2, 19, 0.6, 0.2, 2}};
  in.threshold_db = 18;
  return in;
}
}  // namespace

TEST_CASE("WriteCharts writes data and scripts, and PNG/SVG when gnuplot is there", "[unit]") {
  const fs::path dir = fs::temp_directory_path() / ("p2i_charts_" + std::to_string(getpid()));
  fs::remove_all(dir);
  // No gnuplot: scripts and data only, with a note saying so.
  ChartOutputs out = WriteCharts(Inputs(), (dir / "nognuplot").string(), "p2i-no-such-gnuplot");
  CHECK_FALSE(out.gnuplot_ran);
  CHECK(out.note.find("gnuplot not found") != std::string::npos);
  for (const char* stem : {"accuracy_vs_speed_psnr", "quality_per_setting_psnr", "stability_translation", "ladder"}) {
    INFO(stem);
    CHECK(std::find(out.charts.begin(), out.charts.end(), stem) != out.charts.end());
    CHECK(fs::exists(dir / "nognuplot" / (std::string(stem) + ".gp")));
  }
  // LPIPS missing everywhere: no LPIPS chart rather than a chart of zeros.
  CHECK(std::find(out.charts.begin(), out.charts.end(), "accuracy_vs_speed_lpips") == out.charts.end());
  // The Pareto front of (speed, PSNR): nearest (fastest) and p2i/small (best); p2i/tiny is
  // slower and worse than p2i/small.
  const std::string front = p2i::testing::ReadFile(dir / "nognuplot" / "accuracy_vs_speed_psnr_front.dat");
  CHECK(front.find("nearest/tiny") != std::string::npos);
  CHECK(front.find("p2i/small") != std::string::npos);
  CHECK(front.find("p2i/tiny") == std::string::npos);
  // Missing values are '?' (gnuplot's missing marker), not 0.
  CHECK(p2i::testing::ReadFile(dir / "nognuplot" / "quality_per_setting_psnr.dat").find("?") != std::string::npos);

  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    out = WriteCharts(Inputs(), (dir / "gp").string());
    CHECK(out.gnuplot_ran);
    CHECK(out.note.empty());
    for (const auto& stem : out.charts) {
      INFO(stem);
      CHECK(fs::file_size(dir / "gp" / (stem + ".png")) > 1000);
      CHECK(fs::file_size(dir / "gp" / (stem + ".svg")) > 1000);
    }
  } else {
    WARN("gnuplot not installed: PNG/SVG rendering not checked");
  }
  fs::remove_all(dir);
}

TEST_CASE("Stability summary says where each method falls below the threshold", "[unit]") {
  const auto lines = StabilitySummary(Inputs().stability, {"nearest", "p2i"}, 18);
  REQUIRE(lines.size() == 2);
  CHECK(lines[0].find("falls below 18.0 dB at 0.2 m") != std::string::npos);
  CHECK(lines[1].find("stays above") != std::string::npos);
}

TEST_CASE("ComposeStrip puts ground truth and methods side by side, RGB and depth", "[unit]") {
  const fs::path dir = fs::temp_directory_path() / ("p2i_strip_" + std::to_string(getpid()));
  fs::remove_all(dir);
  p2i::scene::RgbdSample s;
  s.rgb = cv::Mat(32, 32, CV_8UC3, cv::Scalar(200, 10, 10));  // red in RGB order
  s.depth = cv::Mat(32, 32, CV_32FC1, cv::Scalar(2.0f));
  s.depth.at<float>(0, 0) = 0.0f;
  SaveStripView((dir / "ground_truth").string(), 0, s);
  SaveStripView((dir / "m").string(), 0, s);
  CHECK(ComposeStrip(dir.string(), {"ground_truth", "m", "absent"}, 1, (dir / "strip.png").string()));
  const cv::Mat img = cv::imread((dir / "strip.png").string());
  REQUIRE_FALSE(img.empty());
  CHECK(img.rows > 3 * 96);  // 3 rows of cells enlarged to >= 96 px
  CHECK_FALSE(ComposeStrip((dir / "none").string(), {"x"}, 1, (dir / "none.png").string()));
  // Depth colour map: invalid is black, valid is not.
  const cv::Mat c = ColorMapDepth(s.depth, 4.0);
  CHECK(c.at<cv::Vec3b>(0, 0) == cv::Vec3b(0, 0, 0));
  CHECK(c.at<cv::Vec3b>(5, 5) != cv::Vec3b(0, 0, 0));
  fs::remove_all(dir);
}
