/// @file main.cc
/// @brief p2i_monitor: see monitor_node.h.
#include "nodes/monitor/monitor_node.h"

int main(int argc, char** argv) {
  return p2i::runtime::RunNode<p2i::nodes::MonitorNode>(argc, argv);
}
