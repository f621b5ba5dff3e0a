/// @file node_args_test.cc
/// @brief The node command line contract.
#include <catch2/catch.hpp>

#include "nodes/runtime/node_args.h"

using p2i::runtime::NodeArgs;
using p2i::runtime::StartupError;

TEST_CASE("NodeArgs parses every part of the contract", "[unit]") {
  const auto a = NodeArgs::Parse(std::vector<std::string>{
      "--name", "cam", "--namespace", "/robot", "--params-file", "a.yaml",
      "--params-file=b.yaml", "-r", "pose:=/slam/pose", "rate:=30", "size:=[64,64]"});
  CHECK(a.name == "cam");
  CHECK(a.node_namespace == "/robot");
  REQUIRE(a.params_files.size() == 2);
  CHECK(a.params_files[1] == "b.yaml");
  REQUIRE(a.remaps.size() == 1);
  CHECK(a.remaps[0].first == "pose");
  CHECK(a.remaps[0].second == "/slam/pose");
  REQUIRE(a.overrides.size() == 2);
  CHECK(a.overrides[1].first == "size");
  CHECK(a.overrides[1].second == "[64,64]");
  CHECK(a.extra.empty());
  CHECK_FALSE(a.help);
}

TEST_CASE("NodeArgs refuses tokens that are neither NAME:=VALUE nor a known flag", "[unit]") {
  CHECK_THROWS_WITH(NodeArgs::Parse(std::vector<std::string>{"rate=10"}),
                    Catch::Contains("'rate=10'") && Catch::Contains("did you mean rate:=10"));
  CHECK_THROWS_AS(NodeArgs::Parse(std::vector<std::string>{"extra"}), StartupError);
  CHECK_THROWS_AS(NodeArgs::Parse(std::vector<std::string>{"--verbose"}), StartupError);
  const auto h = NodeArgs::Parse(std::vector<std::string>{"--help", "--version"});
  CHECK(h.help);
  CHECK(h.version);
  // ROS 2 spellings.
  const auto r = NodeArgs::Parse(
      std::vector<std::string>{"--ros-args", "-p", "rate:=10", "--remap", "a:=b", "--"});
  REQUIRE(r.overrides.size() == 1);
  CHECK(r.overrides[0].second == "10");
  CHECK(r.remaps.size() == 1);
}

TEST_CASE("NodeArgs rejects a malformed remap and a flag without value", "[unit]") {
  CHECK_THROWS_AS(NodeArgs::Parse(std::vector<std::string>{"-r", "pose"}), StartupError);
  CHECK_THROWS_AS(NodeArgs::Parse(std::vector<std::string>{"--name"}), StartupError);
}
