/// @file main.cc
/// @brief p2i_foxglove_bridge: live p2i topics for Foxglove (docs/RECORDING.md).
#include "nodes/foxglove_bridge/bridge_node.h"

int main(int argc, char** argv) {
  return p2i::runtime::RunNode<p2i::foxglove_bridge::BridgeNode>(argc, argv);
}
