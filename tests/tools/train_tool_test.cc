/// @file train_tool_test.cc
/// @brief `p2i train` as a user runs it: config file, data, progress on the terminal, a JSON-lines
/// log with validation PSNR, a loadable checkpoint, --resume, and clear errors.
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "tests/process_util.h"
#include "tests/temp_dir.h"
#include "tests/test_paths.h"
#include "tests/tiny_config.h"

namespace fs = std::filesystem;

namespace {

// tests/tiny_config.h's model, 6 + 3 steps, validated every 3.
std::string TinyYaml() {
  p2i::model::P2iConfig c = p2i::testing::TinyConfig();
  c.steps_phase1 = 6;
  c.steps_phase2 = 3;
  c.val_every = 3;
  c.Validate();
  return c.ToYamlString();
}

}  // namespace

TEST_CASE("p2i train writes a progress bar, a JSON-lines log and a checkpoint, --resume continues",
          "[integration]") {
  const fs::path dir = p2i::testing::FreshDir("train_tool");
  {
    std::ofstream(dir / "tiny.yaml") << TinyYaml();
  }
  const std::string p2i = p2i::testing::BinDir() + "/p2i";
  const std::string base = p2i + " train " + (dir / "tiny.yaml").string() +
                           " --data procedural --frames 16 --threads 1 --out " +
                           (dir / "run").string();
  int code = -1;
  const std::string out = p2i::testing::RunCommand(base + " 2>&1", &code);
  INFO(out);
  REQUIRE(code == 0);
  CHECK(out.find("phase1") != std::string::npos);  // the progress bar
  CHECK(fs::exists(dir / "run" / "checkpoint.pt"));

  std::ifstream log(dir / "run" / "train_log.jsonl");
  int val_lines = 0;
  bool end = false;
  for (std::string line; std::getline(log, line);) {
    const auto j = nlohmann::json::parse(line);
    if (j.contains("val_psnr") && j.contains("step")) ++val_lines;
    if (j.value("event", "") == "end") end = true;
  }
  CHECK(val_lines >= 2);
  CHECK(end);

  // --resume to more phase-1 steps continues from the checkpoint's step.
  const std::string resumed = p2i::testing::RunCommand(base + " --phase 1 --steps 9 --resume --quiet 2>&1", &code);
  INFO(resumed);
  CHECK(code == 0);
  CHECK(resumed.find("phase 1 9 steps") != std::string::npos);

  // Bad input: a config with an unknown key is refused, naming the key and the file.
  {
    std::ofstream(dir / "bad.yaml") << TinyYaml() << "\nwidht: 3\n";
  }
  const std::string bad = p2i::testing::RunCommand(p2i + " train " + (dir / "bad.yaml").string() +
                                  " --data procedural --out " + (dir / "bad").string() + " 2>&1",
                              &code);
  INFO(bad);
  CHECK(code != 0);
  CHECK(bad.find("widht") != std::string::npos);
  CHECK(bad.find("bad.yaml") != std::string::npos);
  fs::remove_all(dir);
}
