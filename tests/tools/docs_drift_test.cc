/// @file docs_drift_test.cc
/// @brief Docs that drifted from the code once stay true: every calib/*.yaml is listed in
/// docs/CALIBRATION.md; no doc names a build folder other than `build`; the Python sketch of
/// docs/MESSAGES.md connects to the real default endpoint; every `p2i NAME` that a command's
/// --help names is a command; the exit-code rule is documented.
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>

#include "tests/process_util.h"
#include "tests/read_file.h"
#include "tests/test_paths.h"

namespace fs = std::filesystem;

using p2i::testing::ReadFile;

namespace {

std::string Source(const std::string& rel) {
  return ReadFile(fs::path(p2i::testing::SourceDir()) / rel);
}

}  // namespace

TEST_CASE("docs/CALIBRATION.md lists every calib/*.yaml", "[unit]") {
  const std::string doc = Source("docs/CALIBRATION.md");
  for (const auto& e : fs::directory_iterator(fs::path(p2i::testing::SourceDir()) / "calib")) {
    if (e.path().extension() != ".yaml") continue;
    INFO(e.path().filename());
    CHECK(doc.find("calib/" + e.path().filename().string()) != std::string::npos);
  }
}

TEST_CASE("docs name no build folder but build/", "[unit]") {
  const std::regex other(R"((^|[\s`(])build-[A-Za-z0-9_]+/|--test-dir build-)");
  std::vector<fs::path> docs = {fs::path(p2i::testing::SourceDir()) / "README.md"};
  for (const auto& e : fs::directory_iterator(fs::path(p2i::testing::SourceDir()) / "docs"))
    if (e.path().extension() == ".md") docs.push_back(e.path());
  for (const auto& d : docs) {
    std::istringstream lines(ReadFile(d));
    std::string line;
    int n = 0;
    while (std::getline(lines, line)) {
      ++n;
      INFO(d.string() << ":" << n << ": " << line);
      CHECK_FALSE(std::regex_search(line, other));
    }
  }
}

TEST_CASE("the Python sketch of docs/MESSAGES.md uses the real default endpoint", "[unit]") {
  const std::string doc = Source("docs/MESSAGES.md");
  // DefaultEndpoint("topic", "/camera/rgbd") (nodes/runtime/endpoints.cc): '/' -> '.'.
  CHECK(doc.find("topic.camera.rgbd.ipc") != std::string::npos);
  CHECK(doc.find("P2I_RUN_DIR") != std::string::npos);
  CHECK(doc.find("ipc:///tmp/p2i/camera_rgbd") == std::string::npos);
}

TEST_CASE("every `p2i NAME` a command's --help names is a command", "[integration]") {
  const std::string bin = p2i::testing::BinDir() + "/p2i";
  int code = -1;
  const std::string usage = p2i::testing::RunCommand(bin + " --help 2>&1", &code);
  REQUIRE(code == 0);
  std::set<std::string> commands;
  {
    std::istringstream lines(usage);
    std::string line;
    const std::regex row(R"(^  ([a-z]+)\s)");
    std::smatch m;
    while (std::getline(lines, line))
      if (std::regex_search(line, m, row)) commands.insert(m[1]);
  }
  REQUIRE(commands.count("train") == 1);
  for (const auto& c : commands) {
    const std::string help = p2i::testing::RunCommand(bin + " " + c + " --help 2>&1", &code);
    INFO(c << ":\n" << help);
    CHECK(code == 0);
    // The exit-code rule (docs/RUNTIME.md): an unknown option is a usage error, 2, for every
    // command (CLI11's own codes, 100-115, leaked from p2i record/info/play/keygen/refine).
    p2i::testing::RunCommand(bin + " " + c + " --no-such-option 2>&1", &code);
    CHECK(code == 2);
    const std::regex named(R"(\bp2i ([a-z]+)\b)");
    for (std::sregex_iterator it(help.begin(), help.end(), named), end; it != end; ++it) {
      const std::string word = (*it)[1];
      if (word == "capture") continue;  // "p2i capture" is a dataset format (docs/DATASETS.md)
      CHECK(commands.count(word) == 1);
    }
  }
}

TEST_CASE("the exit-code rule is documented", "[unit]") {
  const std::string runtime = Source("docs/RUNTIME.md");
  CHECK(runtime.find("2 = usage or configuration error") != std::string::npos);
}
