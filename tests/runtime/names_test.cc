/// @file names_test.cc
/// @brief Name resolution and remapping.
#include <catch2/catch.hpp>

#include "nodes/runtime/names.h"
#include "nodes/runtime/node_args.h"

using p2i::runtime::NameResolver;

TEST_CASE("NameResolver resolves relative, absolute and private names", "[unit]") {
  NameResolver r("/robot", "cam");
  CHECK(r.Resolve("rgbd") == "/robot/rgbd");
  CHECK(r.Resolve("/tf") == "/tf");
  CHECK(r.Resolve("~/status") == "/robot/cam/status");
  CHECK(r.FullNodeName() == "/robot/cam");
  NameResolver root("/", "cam");
  CHECK(root.Resolve("rgbd") == "/rgbd");
  CHECK(root.Resolve("~status") == "/cam/status");
}

TEST_CASE("NameResolver applies remapping after resolution", "[unit]") {
  NameResolver r("/robot", "cam", {{"pose", "/slam/pose"}, {"/robot/view", "synth/view"}});
  CHECK(r.Resolve("pose") == "/slam/pose");
  CHECK(r.Resolve("/robot/pose") == "/slam/pose");
  CHECK(r.Resolve("view") == "/robot/synth/view");
  CHECK(r.Resolve("pose_est") == "/robot/pose_est");
  CHECK(r.ResolveNoRemap("pose") == "/robot/pose");
}

TEST_CASE("NameResolver rejects invalid names", "[unit]") {
  NameResolver r("/", "n");
  CHECK_THROWS_AS(r.Resolve("a b"), p2i::runtime::StartupError);
  CHECK_THROWS_AS(r.Resolve("a//b"), p2i::runtime::StartupError);
  CHECK_THROWS_AS(NameResolver("/", "a/b"), p2i::runtime::StartupError);
}
