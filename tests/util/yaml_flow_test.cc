/// @file yaml_flow_test.cc
/// @brief util::YamlFlow: maps, lists and scalars as one line of flow text.
#include "util/yaml_flow.h"

#include <catch2/catch.hpp>

using p2i::util::YamlFlow;

TEST_CASE("YamlFlow writes maps, lists and scalars as one line of flow text", "[unit]") {
  CHECK(YamlFlow(YAML::Load("{k: 2, fill_holes: false}")) == "{k: 2, fill_holes: false}");
  CHECK(YamlFlow(YAML::Load("[1, 2, 3]")) == "[1, 2, 3]");
  CHECK(YamlFlow(YAML::Load("{tsdf: {voxel_size_m: 0.02}, blend: [4]}")) ==
        "{tsdf: {voxel_size_m: 0.02}, blend: [4]}");
  CHECK(YamlFlow(YAML::Load("3.5")) == "3.5");
  CHECK(YamlFlow(YAML::Node(std::string())) == "\"\"");
}
