/// @file bench_tool_test.cc
/// @brief `p2i bench` as a user runs it on bench/configs/tiny.yaml: rows, charts, report, strips,
/// resume, and a bad config refused naming key and file.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "tests/process_util.h"
#include "tests/read_file.h"
#include "tests/test_paths.h"

namespace fs = std::filesystem;

namespace {

// Every row of tiny.yaml's results.json: plausible figures, LPIPS null only without weights, and
// the 4:3 size's two rows (nearest and warp on b at 40 x 30, no p2i).
void CheckRows(const nlohmann::json& j) {
  int four_three = 0;
  for (const auto& r : j.at("rows")) {
    if (r.at("size") == "r40x30") {
      ++four_three;
      CHECK(r.at("resolution").get<int>() == 40);
      CHECK(r.at("height").get<int>() == 30);
      CHECK(r.at("setting") == "b");
      CHECK(r.at("method") != "p2i");
    } else {
      CHECK(r.at("height").get<int>() == 32);
    }
    CHECK(r.at("psnr_db").get<double>() > 5.0);
    CHECK(r.at("views_per_s").get<double>() > 0.0);
    CHECK(r.at("test_views").get<int>() > 0);
    if (r.at("method") == "p2i") {
      CHECK(r.at("params").get<double>() > 0);
      CHECK(r.at("train_steps_phase1").get<int>() == 2);
    }
    if (fs::exists(p2i::testing::SharedDir() + "/models/lpips/lpips_squeeze_v0.1.pth"))
      CHECK(r.at("lpips_squeeze").is_number());
    else
      CHECK(r.at("lpips_squeeze").is_null());  // missing, never 0
  }
  CHECK(four_three == 2);
}

}  // namespace

TEST_CASE("p2i bench runs the tiny config end to end and resumes", "[integration]") {
  const fs::path dir = fs::temp_directory_path() / ("p2i_bench_tool_" + std::to_string(getpid()));
  fs::remove_all(dir);
  const std::string p2i = p2i::testing::BinDir() + "/p2i";
  const std::string config = p2i::testing::SourceDir() + "/bench/configs/tiny.yaml";
  const std::string cmd = p2i + " bench " + config + " --out " + (dir / "out").string() +
                          " --lpips-weights " + p2i::testing::SharedDir() +
                          "/models/lpips/lpips_squeeze_v0.1.pth 2>&1";
  int code = -1;
  const std::string out = p2i::testing::RunCommand(cmd, &code);
  INFO(out);
  REQUIRE(code == 0);

  // 3 methods x 4 settings at r32, + nearest and warp on b at r40x30 (4:3; p2i skips it).
  std::ifstream csv(dir / "out" / "results.csv");
  std::string line;
  int rows = 0;
  std::getline(csv, line);
  CHECK(line.rfind("method,method_type,setting,size", 0) == 0);
  while (std::getline(csv, line)) ++rows;
  CHECK(rows == 14);
  std::ifstream js(dir / "out" / "results.json");
  const auto j = nlohmann::json::parse(js);
  REQUIRE(j.at("rows").size() == 14);
  CheckRows(j);
  // Charts (PNG + SVG with gnuplot, else scripts), report, strips, stability, splits.
  const bool gnuplot = std::system("command -v gnuplot >/dev/null 2>&1") == 0;
  for (const char* stem : {"accuracy_vs_speed_psnr", "quality_per_setting_psnr", "stability_translation",
                           "stability_rotation"}) {
    INFO(stem);
    CHECK(fs::exists(dir / "out" / "charts" / (std::string(stem) + ".gp")));
    if (gnuplot) {
      CHECK(fs::exists(dir / "out" / "charts" / (std::string(stem) + ".png")));
      CHECK(fs::exists(dir / "out" / "charts" / (std::string(stem) + ".svg")));
    }
  }
  for (const char* s : {"a1", "a3", "b", "c"}) {
    CHECK(fs::exists(dir / "out" / "strips" / (std::string(s) + ".png")));
    CHECK(fs::exists(dir / "out" / "splits" / (std::string(s) + ".yaml")));
  }
  CHECK(fs::exists(dir / "out" / "stability.csv"));
  const std::string report = p2i::testing::ReadFile(dir / "out" / "report.md");
  CHECK(report.find("| p2i | c | r32 | 1 |") != std::string::npos);
  CHECK(report.find("Image strips") != std::string::npos);
  CHECK(report.find("falls below") != std::string::npos);

  // A second run resumes: nothing is recomputed, the rows stay.
  const std::string again = p2i::testing::RunCommand(cmd, &code);
  INFO(again);
  CHECK(code == 0);
  CHECK(again.find("resuming: 14 row(s)") != std::string::npos);
  CHECK(again.find("training") == std::string::npos);

  // Bad config: refused at start-up naming the key and the file.
  std::ofstream(dir / "bad.yaml") << p2i::testing::ReadFile(config) << "treads: 2\n";
  const std::string bad = p2i::testing::RunCommand(
      p2i + " bench " + (dir / "bad.yaml").string() + " --out " + (dir / "bad").string() + " 2>&1", &code);
  INFO(bad);
  CHECK(code != 0);
  CHECK(bad.find("treads") != std::string::npos);
  CHECK(bad.find("bad.yaml") != std::string::npos);
  fs::remove_all(dir);
}
