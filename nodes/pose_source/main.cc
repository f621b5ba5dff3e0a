/// @file main.cc
/// @brief p2i_pose_source: see pose_source_node.h.
#include "nodes/pose_source/pose_source_node.h"

int main(int argc, char** argv) {
  return p2i::runtime::RunNode<p2i::nodes::PoseSourceNode>(argc, argv);
}
