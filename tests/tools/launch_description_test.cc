/// @file launch_description_test.cc
/// @brief Launch YAML reader: args, overrides, $(var), include, groups, errors; command lines.
#include "tools/launch_description.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include "tests/temp_dir.h"
#include "tools/launch_command.h"

using p2i::tools::BuildNodeCommand;
using p2i::tools::JoinNamespace;
using p2i::tools::LaunchDescription;
using p2i::tools::LaunchDescriptionReader;
using p2i::tools::LaunchError;
using p2i::tools::NodeDescription;
using p2i::tools::SplitShellWords;
namespace fs = std::filesystem;

namespace {

using p2i::testing::TempDir;

std::string ErrorOf(const std::string& file, const std::map<std::string, std::string>& o = {}) {
  try {
    LaunchDescriptionReader::ReadFile(file, o);
  } catch (const LaunchError& e) {
    return e.what();
  }
  return "";
}

const NodeDescription& NodeNamed(const LaunchDescription& d, const std::string& name) {
  for (const auto& n : d.nodes) {
    if (n.DisplayName() == name) return n;
  }
  FAIL("no node named " << name);
  throw 0;
}

}  // namespace

TEST_CASE("Launch args: defaults, command-line overrides and $(var)", "[unit]") {
  TempDir dir;
  const std::string file = dir.Write("a.yaml", R"Y(launch:
- arg: {name: rate, default: "30", description: "frames per second"}
- arg: {name: cam_name, default: "cam"}
- let: {name: topic, value: "/$(var cam_name)/rgbd"}
- node:
    pkg: p2i
    exec: camera
    name: $(var cam_name)
    param:
    - {name: rate, value: "$(var rate)"}
    - {name: size, value: [64, "$(var rate)"]}
    remap:
    - {from: rgbd, to: "$(var topic)"}
    args: "--verbose --label 'two words' $(var rate)"
)Y");
  const LaunchDescription d = LaunchDescriptionReader::ReadFile(file);
  REQUIRE(d.nodes.size() == 1);
  const NodeDescription& n = d.nodes[0];
  CHECK(n.exec == "camera");
  CHECK(n.pkg == "p2i");
  CHECK(n.name == "cam");
  CHECK(n.node_namespace == "/");
  REQUIRE(n.params.size() == 2);
  CHECK(n.params[0].name == "rate");
  CHECK(n.params[0].value_yaml == "30");
  CHECK(n.params[1].value_yaml == "[64, 30]");
  REQUIRE(n.remaps.size() == 1);
  CHECK(n.remaps[0].first == "rgbd");
  CHECK(n.remaps[0].second == "/cam/rgbd");
  CHECK(n.args == std::vector<std::string>{"--verbose", "--label", "two words", "30"});
  CHECK(n.source == fs::absolute(file).lexically_normal().string() + ":5");
  REQUIRE(d.arguments.size() == 2);
  CHECK(d.arguments[0].description == "frames per second");

  const LaunchDescription o =
      LaunchDescriptionReader::ReadFile(file, {{"rate", "60"}, {"cam_name", "left"}});
  CHECK(o.nodes[0].name == "left");
  CHECK(o.nodes[0].params[0].value_yaml == "60");
  CHECK(o.nodes[0].remaps[0].second == "/left/rgbd");
  CHECK(o.top_level_vars.at("topic") == "/left/rgbd");
}

TEST_CASE("Launch: a missing required arg says how to pass it", "[unit]") {
  TempDir dir;
  const std::string file = dir.Write("req.yaml", R"Y(launch:
- arg: {name: rate, default: "1"}
- arg: {name: scene}
- node: {exec: camera, args: "$(var scene)"}
)Y");
  const std::string e = ErrorOf(file);
  CHECK_THAT(e, Catch::Contains("req.yaml:3"));
  CHECK_THAT(e, Catch::Contains("'scene'"));
  CHECK_THAT(e, Catch::Contains("scene:=VALUE"));
  CHECK(LaunchDescriptionReader::ReadFile(file, {{"scene", "office"}}).nodes[0].args ==
        std::vector<std::string>{"office"});
  // An override no arg declares is a typo, not silently ignored.
  const std::string typo = ErrorOf(file, {{"scene", "x"}, {"scen", "y"}});
  CHECK_THAT(typo, Catch::Contains("'scen:=y'"));
  CHECK_THAT(typo, Catch::Contains("rate, scene"));
}

TEST_CASE("Launch: unknown keys and bad values name file, line and key", "[unit]") {
  TempDir dir;
  const std::string file = dir.Write("bad.yaml", R"Y(launch:
- arg: {name: rate, default: "1"}
- node:
    exec: camera
    respwan: true
)Y");
  const std::string e = ErrorOf(file);
  CHECK_THAT(e, Catch::Contains("bad.yaml:5"));
  CHECK_THAT(e, Catch::Contains("respwan"));
  CHECK_THAT(e, Catch::Contains("respawn_delay"));  // the list of allowed keys

  const std::string entity = ErrorOf(dir.Write("e.yaml", "launch:\n- nod: {exec: x}\n"));
  CHECK_THAT(entity, Catch::Contains("e.yaml:2"));
  CHECK_THAT(entity, Catch::Contains("'nod'"));

  const std::string var = ErrorOf(dir.Write("v.yaml", R"Y(launch:
- arg: {name: rate, default: "1"}
- node:
    exec: camera
    args: "$(var rat)"
)Y"));
  CHECK_THAT(var, Catch::Contains("v.yaml:5"));
  CHECK_THAT(var, Catch::Contains("'rat'"));
  CHECK_THAT(var, Catch::Contains("known: rate"));

  const std::string top = ErrorOf(dir.Write("t.yaml", "launch: []\nnodes: []\n"));
  CHECK_THAT(top, Catch::Contains("t.yaml:2"));
  CHECK_THAT(top, Catch::Contains("'nodes'"));

  const std::string boolean =
      ErrorOf(dir.Write("b.yaml", "launch:\n- node: {exec: a, respawn: maybe}\n"));
  CHECK_THAT(boolean, Catch::Contains("b.yaml:2"));
  CHECK_THAT(boolean, Catch::Contains("'respawn'"));

  const std::string both = ErrorOf(
      dir.Write("rr.yaml", "launch:\n- node: {exec: a, respawn: true, required: true}\n"));
  CHECK_THAT(both, Catch::Contains("both"));

  const std::string dup = ErrorOf(
      dir.Write("d.yaml", "launch:\n- node: {exec: a, name: x}\n- node: {exec: b, name: x}\n"));
  CHECK_THAT(dup, Catch::Contains("d.yaml:3"));
  CHECK_THAT(dup, Catch::Contains("/x"));
  CHECK_THAT(dup, Catch::Contains("d.yaml:2"));

  const std::string syntax = ErrorOf(dir.Write("s.yaml", "launch:\n- node: {exec: [a\n"));
  CHECK_THAT(syntax, Catch::Contains("s.yaml:"));
  CHECK_THAT(syntax, Catch::Contains("syntax"));

  const std::string from = ErrorOf(
      dir.Write("f.yaml", "launch:\n- node:\n    exec: a\n    param: [{from: nope.yaml}]\n"));
  CHECK_THAT(from, Catch::Contains("f.yaml:4"));
  CHECK_THAT(from, Catch::Contains("nope.yaml"));
}

TEST_CASE("Launch: include with args, $(dirname) and relative paths", "[unit]") {
  TempDir dir;
  dir.Write("sub/params.yaml", "rate: 5\n");
  dir.Write("sub/camera.yaml", R"Y(launch:
- arg: {name: cam}
- arg: {name: rate, default: "15"}
- node:
    exec: camera
    name: $(var cam)
    param:
    - {from: params.yaml}
    - {name: rate, value: "$(var rate)"}
    - {from: "$(dirname)/params.yaml"}
    args: "$(var outer)"
)Y");
  const std::string top = dir.Write("top.yaml", R"Y(launch:
- arg: {name: outer, default: "o"}
- include:
    file: sub/camera.yaml
    arg:
    - {name: cam, value: left}
- include:
    file: "$(dirname)/sub/camera.yaml"
    arg:
    - {name: cam, value: right}
    - {name: rate, value: "7"}
)Y");
  const LaunchDescription d = LaunchDescriptionReader::ReadFile(top, {{"outer", "X"}});
  REQUIRE(d.nodes.size() == 2);
  const NodeDescription& left = NodeNamed(d, "left");
  const NodeDescription& right = NodeNamed(d, "right");
  const std::string params = fs::absolute(dir.path() + "/sub/params.yaml").lexically_normal();
  REQUIRE(left.params.size() == 3);
  CHECK(left.params[0].from_file == params);
  CHECK(left.params[1].value_yaml == "15");  // the included file's default
  CHECK(left.params[2].from_file == params);
  CHECK(right.params[1].value_yaml == "7");  // the include's argument wins
  CHECK(left.args == std::vector<std::string>{"X"});  // command-line vars reach includes
  CHECK_THAT(left.source, Catch::Contains("sub/camera.yaml:4"));

  // The include does not pass `cam`: the error points at the include site.
  const std::string bad = dir.Write("bad.yaml", "launch:\n- include: {file: sub/camera.yaml}\n");
  const std::string e = ErrorOf(bad);
  CHECK_THAT(e, Catch::Contains("camera.yaml:2"));
  CHECK_THAT(e, Catch::Contains("bad.yaml:2"));
  CHECK_THAT(e, Catch::Contains("cam"));

  const std::string cycle = dir.Write("cycle.yaml", "launch:\n- include: {file: cycle.yaml}\n");
  CHECK_THAT(ErrorOf(cycle), Catch::Contains("include cycle"));
}

TEST_CASE("Launch: groups push namespaces and scope their variables", "[unit]") {
  TempDir dir;
  const std::string file = dir.Write("g.yaml", R"Y(launch:
- arg: {name: robot, default: "r1"}
- let: {name: v, value: outer}
- group:
  - push-ros-namespace: {namespace: "$(var robot)"}
  - let: {name: v, value: inner}
  - node: {exec: camera, name: cam, args: "$(var v)"}
  - node: {exec: camera, name: cam2, namespace: sensors}
  - node: {exec: camera, name: cam3, namespace: /abs}
  - group:
      namespace: deeper
      children:
      - node: {exec: sink, name: sink}
- node: {exec: camera, name: top, args: "$(var v)"}
- group: {namespace: /x/, launch: [{node: {exec: camera}}]}
)Y");
  const LaunchDescription d = LaunchDescriptionReader::ReadFile(file);
  REQUIRE(d.nodes.size() == 6);
  CHECK(NodeNamed(d, "cam").node_namespace == "/r1");
  CHECK(NodeNamed(d, "cam").args == std::vector<std::string>{"inner"});
  CHECK(NodeNamed(d, "cam2").node_namespace == "/r1/sensors");
  CHECK(NodeNamed(d, "cam3").node_namespace == "/abs");
  CHECK(NodeNamed(d, "sink").node_namespace == "/r1/deeper");
  CHECK(NodeNamed(d, "top").node_namespace == "/");
  CHECK(NodeNamed(d, "top").args == std::vector<std::string>{"outer"});
  CHECK(NodeNamed(d, "camera").node_namespace == "/x");
  const LaunchDescription o = LaunchDescriptionReader::ReadFile(file, {{"robot", "r2/front"}});
  CHECK(NodeNamed(o, "sink").node_namespace == "/r2/front/deeper");
}

TEST_CASE("Launch: node command line follows the node CLI contract", "[unit]") {
  NodeDescription n;
  n.exec = "camera";
  n.name = "cam";
  n.node_namespace = "/robot";
  n.params = {{"", "rate", "30"}, {"", "size", "[64, 64]"}, {"/cfg/a.yaml", "", ""},
              {"", "label", "x"}};
  n.remaps = {{"rgbd", "/robot/rgbd"}};
  n.args = {"--extra", "1"};
  const auto cmd = BuildNodeCommand(n, "/bin/p2i_camera", "/tmp/params", 3);
  REQUIRE(cmd.param_files.size() == 2);
  CHECK(cmd.param_files[0].first == "/tmp/params/3_cam.0.yaml");
  CHECK(cmd.param_files[0].second == "rate: 30\nsize: [64, 64]\n");
  CHECK(cmd.param_files[1].second == "label: x\n");
  const std::vector<std::string> expected = {
      "/bin/p2i_camera", "--name", "cam", "--namespace", "/robot",
      "--params-file", cmd.param_files[0].first, "--params-file", "/cfg/a.yaml",
      "--params-file", cmd.param_files[1].first, "-r", "rgbd:=/robot/rgbd", "--extra", "1"};
  CHECK(cmd.argv == expected);

  NodeDescription bare;
  bare.exec = "sink";
  const auto b = BuildNodeCommand(bare, "p2i_sink", "/tmp", 0);
  CHECK(b.argv == std::vector<std::string>{"p2i_sink", "--namespace", "/"});
  CHECK(b.display_name == "sink");
}

TEST_CASE("Launch helpers: shell words, namespaces, overrides", "[unit]") {
  CHECK(SplitShellWords("  a 'b c'  \"d e\" f\\ g  ") ==
        std::vector<std::string>{"a", "b c", "d e", "f g"});
  CHECK(SplitShellWords("").empty());
  CHECK_THROWS_AS(SplitShellWords("a 'b"), std::invalid_argument);
  CHECK(JoinNamespace("/", "") == "/");
  CHECK(JoinNamespace("/a", "b/") == "/a/b");
  CHECK(JoinNamespace("/a", "/c") == "/c");
  CHECK(JoinNamespace("/a//b/", "") == "/a/b");
  const auto o = p2i::tools::ParseLaunchOverrides({"a:=1", "b:=x:=y", "c:="});
  CHECK(o.at("a") == "1");
  CHECK(o.at("b") == "x:=y");
  CHECK(o.at("c").empty());
  CHECK_THROWS_AS(p2i::tools::ParseLaunchOverrides({"a=1"}), LaunchError);
  CHECK(p2i::tools::ShellQuote("a b") == "'a b'");
  CHECK(p2i::tools::ShellQuote("--name") == "--name");
}

TEST_CASE("Launch: a key given twice in one map is an error naming both lines", "[unit]") {
  const std::string text =
      "launch:\n"
      "- node:\n"
      "    exec: camera\n"
      "    name: cam\n"
      "    exec: pose_source\n";
  CHECK_THROWS_WITH(p2i::tools::LaunchDescriptionReader::ReadString(text, "/x/dup.yaml"),
                    Catch::Contains("/x/dup.yaml:5") && Catch::Contains("key 'exec'") &&
                        Catch::Contains("duplicate key (first at line 3)"));
}

TEST_CASE("Launch: inline parameter lines carry their launch file line", "[unit]") {
  const std::string text =
      "launch:\n"
      "- node:\n"
      "    exec: camera\n"
      "    param:\n"
      "    - {name: rate, value: 5}\n";
  const auto d = p2i::tools::LaunchDescriptionReader::ReadString(text, "/x/l.yaml");
  const auto cmd = p2i::tools::BuildNodeCommand(d.nodes.at(0), "/bin/p2i_camera", "/tmp/p", 0);
  REQUIRE(cmd.param_files.size() == 1);
  CHECK(cmd.param_files[0].second == "rate: 5  #@ /x/l.yaml:5\n");
}
