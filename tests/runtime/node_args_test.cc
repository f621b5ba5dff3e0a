/// @file node_args_test.cc
/// @brief The node command line contract.
#include <catch2/catch.hpp>

#include "nodes/runtime/node_args.h"

using p2i::runtime::NodeArgs;
using p2i::runtime::StartupError;

TEST_CASE("NodeArgs parses every part of the contract", "[unit]") {
  const auto a = NodeArgs::Parse(std::vector<std::string>{
      "--name", "cam", "--namespace", "/robot", "--params-file", "a.yaml",
      "--params-file=b.yaml", "-r", "pose:=/slam/pose", "rate:=30", "size:=[64,64]", "extra"});
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
  REQUIRE(a.extra.size() == 1);
  CHECK(a.extra[0] == "extra");
}

TEST_CASE("NodeArgs rejects a malformed remap and a flag without value", "[unit]") {
  CHECK_THROWS_AS(NodeArgs::Parse(std::vector<std::string>{"-r", "pose"}), StartupError);
  CHECK_THROWS_AS(NodeArgs::Parse(std::vector<std::string>{"--name"}), StartupError);
}
