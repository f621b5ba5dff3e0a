/// @file launch_machine_test.cc
/// @brief Multi-host launch files: `machine` entities, each node's machine, and which nodes a
/// host starts (--machine or its own address); the error texts.
#include "tools/launch_machine.h"

#include <catch2/catch.hpp>

using p2i::tools::LaunchDescription;
using p2i::tools::LaunchDescriptionReader;
using p2i::tools::LaunchError;
using p2i::tools::MachinePlan;
using p2i::tools::PlanMachine;

namespace {

const char* kTwoHosts = R"YAML(launch:
- arg: {name: robot_address, default: "10.231.0.1"}
- machine: {name: robot, address: "$(var robot_address)"}
- machine: {name: workstation, address: 10.231.0.2, discovery_port: 7500}
- node: {exec: camera, machine: robot}
- node: {exec: trainer, machine: workstation}
- node: {exec: pose_source, machine: robot}
)YAML";

LaunchDescription Read(const std::string& text) {
  return LaunchDescriptionReader::ReadString(text, "/tmp/two.yaml");
}

}  // namespace

TEST_CASE("Launch machines: each host starts its own nodes and knows the others' registries", "[unit]") {
  const LaunchDescription d = Read(kTwoHosts);
  REQUIRE(d.machines.size() == 2);
  CHECK(d.machines[0].address == "10.231.0.1");
  CHECK(d.machines[0].discovery_port == 7411);
  CHECK(d.machines[1].RegistryEndpoint() == "tcp://10.231.0.2:7500");

  const MachinePlan robot = PlanMachine(d, "robot");
  CHECK(robot.multi_host);
  REQUIRE(robot.nodes.size() == 2);
  CHECK(robot.nodes[0].exec == "camera");
  CHECK(robot.nodes[1].exec == "pose_source");
  CHECK(robot.PeersText() == "tcp://10.231.0.2:7500");

  // Without --machine: the machine whose address this host has.
  const MachinePlan ws = PlanMachine(d, "", {"127.0.0.1", "10.231.0.2"});
  CHECK(ws.self.name == "workstation");
  REQUIRE(ws.nodes.size() == 1);
  CHECK(ws.nodes[0].exec == "trainer");
  CHECK(ws.PeersText() == "tcp://10.231.0.1:7411");

  CHECK_THROWS_WITH(PlanMachine(d, "", {"127.0.0.1"}),
                    Catch::Contains("none of the launch file's machines") &&
                        Catch::Contains("--machine NAME"));
  CHECK_THROWS_WITH(PlanMachine(d, "laptop"), Catch::Contains("not declared"));

  // A file without machines: everything, single host.
  const LaunchDescription one = Read("launch:\n- node: {exec: camera}\n");
  CHECK_FALSE(PlanMachine(one, "").multi_host);
  CHECK(PlanMachine(one, "").nodes.size() == 1);
  CHECK_THROWS_WITH(PlanMachine(one, "robot"), Catch::Contains("declares no machines"));
}

TEST_CASE("Launch machines: errors name the file, line and key", "[unit]") {
  CHECK_THROWS_WITH(Read("launch:\n- machine: {name: a, address: 10.0.0.1}\n- node: {exec: camera}\n"),
                    Catch::Contains("/tmp/two.yaml:3") && Catch::Contains("names no `machine:`"));
  CHECK_THROWS_WITH(
      Read("launch:\n- machine: {name: a, address: 10.0.0.1}\n- node: {exec: camera, machine: b}\n"),
      Catch::Contains("machine 'b' is not declared") && Catch::Contains("declared: a"));
  CHECK_THROWS_WITH(Read("launch:\n- machine: {name: a, address: 'tcp://10.0.0.1:5'}\n"),
                    Catch::Contains("key 'address'"));
  CHECK_THROWS_WITH(Read("launch:\n- machine: {name: a, address: h, discovery_port: 70000}\n"),
                    Catch::Contains("key 'discovery_port'"));
  CHECK_THROWS_WITH(Read("launch:\n- machine: {name: a, address: h}\n- machine: {name: a, address: g}\n"),
                    Catch::Contains("a second machine 'a'"));
  CHECK_THROWS_WITH(Read("launch:\n- machine: {name: a, adress: h}\n"),
                    Catch::Contains("unknown key in machine"));
}
