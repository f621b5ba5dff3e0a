/// @file parameters_test.cc
/// @brief Parameter precedence, types and the unknown-parameter error.
#include <catch2/catch.hpp>

#include <fstream>

#include "nodes/runtime/parameters.h"
#include "tests/runtime/test_util.h"

using p2i::runtime::NodeArgs;
using p2i::runtime::Parameters;
using p2i::runtime::StartupError;

namespace {
std::string WriteFile(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}
}  // namespace

TEST_CASE("Parameters: default < first file < second file < command line", "[unit]") {
  p2i::runtime::testing::ScopedRunDir dir;
  const auto f1 = WriteFile(dir.Path(), "a.yaml", "rate: 10\nsize: [32, 32]\nlabel: a\n");
  const auto f2 = WriteFile(dir.Path(), "b.yaml", "rate: 20\nlabel: b\n");
  NodeArgs args;
  args.params_files = {f1, f2};
  args.overrides = {{"label", "cli"}};
  Parameters p(args);
  CHECK(p.Declare<double>("rate", 30.0, "frames per second") == 20.0);
  CHECK(p.Declare<std::vector<int>>("size", {64, 64}, "size") == std::vector<int>{32, 32});
  CHECK(p.Declare<std::string>("label", "none", "label") == "cli");
  CHECK(p.Declare<bool>("flag", true, "a flag") == true);
  CHECK(p.Declared().at("rate").source == f2);
  CHECK(p.Declared().at("label").source == "command line");
  CHECK(p.Declared().at("flag").source == "default");
  CHECK_NOTHROW(p.CheckAllDeclared());
}

TEST_CASE("Parameters: an unknown parameter names itself and its source", "[unit]") {
  p2i::runtime::testing::ScopedRunDir dir;
  const auto f = WriteFile(dir.Path(), "p.yaml", "rate: 5\nratee: 6\n");
  NodeArgs args;
  args.params_files = {f};
  args.overrides = {{"colour", "red"}};
  Parameters p(args);
  p.Declare<double>("rate", 1.0, "rate");
  try {
    p.CheckAllDeclared();
    FAIL("expected StartupError");
  } catch (const StartupError& e) {
    const std::string what = e.what();
    CHECK(what.find("'ratee'") != std::string::npos);
    CHECK(what.find(f) != std::string::npos);
    CHECK(what.find("'colour'") != std::string::npos);
    CHECK(what.find("command line") != std::string::npos);
  }
}

TEST_CASE("Parameters: a value of the wrong type is a start-up error", "[unit]") {
  NodeArgs args;
  args.overrides = {{"rate", "fast"}};
  Parameters p(args);
  try {
    p.Declare<double>("rate", 1.0, "rate");
    FAIL("expected StartupError");
  } catch (const StartupError& e) {
    CHECK(std::string(e.what()).find("rate") != std::string::npos);
    CHECK(std::string(e.what()).find("command line") != std::string::npos);
  }
}

TEST_CASE("Parameters: overrides take flow maps and a missing file is an error", "[unit]") {
  NodeArgs args;
  args.overrides = {{"endpoints", "{rgbd: tcp://127.0.0.1:5555}"}};
  Parameters p(args);
  const auto m = p.Declare<std::map<std::string, std::string>>("endpoints", {}, "eps");
  CHECK(m.at("rgbd") == "tcp://127.0.0.1:5555");
  Parameters q;
  CHECK_THROWS_AS(q.LoadFile("/nonexistent/p2i/params.yaml"), StartupError);
}
