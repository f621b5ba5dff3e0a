/// @file bench_runner_test.cc
/// @brief RunBench refuses a config whose settings cannot run on its data before the first row
/// (issue 15 item 5): setting b on one trajectory used to fail after setting a1's rows.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <catch2/catch.hpp>

#include "eval/bench_runner.h"
#include "tests/skip.h"
#include "tests/test_paths.h"

namespace fs = std::filesystem;

TEST_CASE("p2i bench: a setting the data cannot run fails before the first row", "[unit]") {
  const fs::path dir = fs::temp_directory_path() / ("p2i_bench_runner_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string config = (dir / "one_trajectory.yaml").string();
  std::ofstream(config) << "dataset: {scene: builtin:small_office, trajectories: 1, frame_step: 12,"
                           " max_frames: 16}\n"
                           "settings: [a1, b]\n"
                           "period: 8\n"
                           "max_test_views: 2\n"
                           "methods: [nearest]\n"
                           "sizes: [{name: r16, resolution: 16}]\n"
                           "threads: 1\n"
                           "strip_views: 0\n";
  p2i::eval::BenchOptions o;
  o.config_path = config;
  o.out_dir = (dir / "out").string();
  o.quiet = true;
  std::string error;
  try {
    p2i::eval::RunBench(o);
  } catch (const std::invalid_argument& e) {  // a configuration error: p2i exits 2
    error = e.what();
  }
  CHECK(error.find("setting b needs 2 sequences") != std::string::npos);
  CHECK(error.find("one_trajectory.yaml") != std::string::npos);
  // No row was measured (a1 comes first in the config).
  CHECK_FALSE(fs::exists(dir / "out" / "results.csv"));
  CHECK_FALSE(fs::exists(dir / "out" / "results.json"));
  fs::remove_all(dir);
}

TEST_CASE("p2i bench: dataset.sequences keeps only the named sequences of a folder", "[unit]") {
  const std::string study_room = p2i::testing::SharedDir() + "/data/study-room";
  if (!fs::is_directory(study_room)) {
    P2I_SKIP("real data not found at " << study_room << " (set P2I_SHARED_DIR)");
  }
  const fs::path dir = fs::temp_directory_path() / ("p2i_bench_seqs_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  auto run = [&](const std::string& sequences) {
    const std::string config = (dir / "seqs.yaml").string();
    std::ofstream(config) << "dataset: {path: " << study_room
                          << ", seven_scenes_invalid_depth: 0, sequences: " << sequences << "}\n"
                          << "settings: [a1, b]\nperiod: 10\nmax_test_views: 2\n"
                             "methods: [nearest]\nsizes: [{name: r16, resolution: 16}]\n"
                             "threads: 1\nstrip_views: 0\n";
    p2i::eval::BenchOptions o;
    o.config_path = config;
    o.out_dir = (dir / "out").string();
    o.quiet = true;
    try {
      p2i::eval::RunBench(o);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // Both sequences of the folder: setting b (train seq-01, test seq-02) has what it needs; one
  // named sequence leaves setting b without its second trajectory.
  CHECK(run("[seq-01]").find("setting b needs 2 sequences") != std::string::npos);
  const std::string unknown = run("[seq-09]");
  CHECK(unknown.find("seq-09") != std::string::npos);
  CHECK(unknown.find("seq-01, seq-02") != std::string::npos);
  fs::remove_all(dir);
}
