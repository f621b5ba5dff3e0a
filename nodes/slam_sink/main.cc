/// @file main.cc
/// @brief p2i_slam_sink: see slam_sink_node.h.
#include "nodes/slam_sink/slam_sink_node.h"

int main(int argc, char** argv) {
  return p2i::runtime::RunNode<p2i::slam_sink::SlamSinkNode>(argc, argv);
}
