/// @file main.cc
/// @brief p2i_synthesizer: the view synthesis node (see docs/SYNTHESIZER.md).
#include "nodes/runtime/node.h"
#include "nodes/synthesizer/synthesizer_node.h"

int main(int argc, char** argv) {
  return p2i::runtime::RunNode<p2i::nodes::SynthesizerNode>(argc, argv);
}
